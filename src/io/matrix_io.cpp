// matrix_i.mat: int32 K, then K + 2 row-major float32 4x4 matrices, all little-endian. Bytes are
// decoded explicitly so the reader does not depend on the host's byte order.
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

constexpr std::int64_t kMatrixBytes = 16 * 4;

std::uint32_t loadLittleEndian32(const unsigned char* p) {
    return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
           (std::uint32_t(p[3]) << 24);
}

Matrix4 decodeMatrix(const std::filesystem::path& file, const unsigned char* bytes, int index) {
    Matrix4 matrix;
    for (int row = 0; row < 4; ++row) {
        for (int col = 0; col < 4; ++col) {
            const float value =
                std::bit_cast<float>(loadLittleEndian32(bytes + 4 * (4 * row + col)));
            if (!std::isfinite(value)) {
                throw Error(ErrorCode::InvalidInput,
                            file.string() + ": matrix " + std::to_string(index) + " has a " +
                                "non-finite value at row " + std::to_string(row) + ", column " +
                                std::to_string(col));
            }
            matrix.m[row][col] = value;
        }
    }
    return matrix;
}

}  // namespace

MatrixFile readMatrixFile(const std::filesystem::path& file) {
    io_detail::requireRegularFile(file, "a .mat file");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error(ErrorCode::IoFailure, file.string() + ": cannot open for reading");
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                           std::istreambuf_iterator<char>());
    if (in.bad()) throw Error(ErrorCode::IoFailure, file.string() + ": read error");

    const auto size = static_cast<std::int64_t>(bytes.size());
    if (size < 4) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": " + std::to_string(size) +
                        " bytes, too short to hold the int32 matrix count");
    }
    const auto count = static_cast<std::int32_t>(loadLittleEndian32(bytes.data()));
    if (count < 0) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": negative matrix count K = " + std::to_string(count));
    }
    const std::int64_t expected = 4 + (std::int64_t(count) + 2) * kMatrixBytes;
    if (size != expected) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": K = " + std::to_string(count) +
                        " needs 4 + (K+2)*64 = " + std::to_string(expected) +
                        " bytes, but the file has " + std::to_string(size));
    }

    MatrixFile result;
    result.objectToWorld.reserve(count);
    const unsigned char* p = bytes.data() + 4;
    for (int k = 0; k < count; ++k, p += kMatrixBytes) {
        result.objectToWorld.push_back(decodeMatrix(file, p, k));
    }
    result.worldToCamera = decodeMatrix(file, p, count);
    result.worldToScreen = decodeMatrix(file, p + kMatrixBytes, count + 1);
    return result;
}

void writeMatrixFile(const std::filesystem::path& file, const MatrixFile& matrices) {
    std::string bytes;
    auto append32 = [&bytes](std::uint32_t v) {
        for (int b = 0; b < 4; ++b) bytes.push_back(char((v >> (8 * b)) & 0xffu));
    };
    auto appendMatrix = [&](const Matrix4& m) {
        for (int row = 0; row < 4; ++row)
            for (int col = 0; col < 4; ++col) append32(std::bit_cast<std::uint32_t>(m.m[row][col]));
    };
    append32(std::uint32_t(matrices.objectToWorld.size()));
    for (const Matrix4& m : matrices.objectToWorld) appendMatrix(m);
    appendMatrix(matrices.worldToCamera);
    appendMatrix(matrices.worldToScreen);
    writeFileAtomically(file, bytes);
}

}  // namespace rtd
