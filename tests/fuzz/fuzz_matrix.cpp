// libFuzzer target: rtd::readMatrixFile (matrix_i.mat: int32 K, K + 2 float32 4x4 matrices) on
// arbitrary bytes. An rtd::Error is the expected outcome; a crash, a leak, undefined behaviour,
// a huge allocation, another exception, or an accepted file that breaks the format's rules
// (its length, finite values, a write-read round trip) is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "fuzz_support.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::filesystem::path folder = rtd::fuzz::scratchFolder("matrix");
    static const std::filesystem::path file = folder / "matrix_0.mat";
    static const std::filesystem::path copy = folder / "copy.mat";
    rtd::fuzz::writeBytes(file, data, size);
    rtd::MatrixFile m;
    try {
        m = rtd::readMatrixFile(file);
    } catch (const rtd::Error&) {
        return 0;
    }
    RTD_FUZZ_CHECK(size == 4 + (m.objectToWorld.size() + 2) * 64);
    std::int32_t count = 0;
    std::memcpy(&count, data, 4);  // little-endian host (x86-64)
    RTD_FUZZ_CHECK(count >= 0 && std::size_t(count) == m.objectToWorld.size());
    auto finite = [](const rtd::Matrix4& a) {
        for (const auto& row : a.m)
            for (float v : row)
                if (!std::isfinite(v)) return false;
        return true;
    };
    for (const rtd::Matrix4& a : m.objectToWorld) RTD_FUZZ_CHECK(finite(a));
    RTD_FUZZ_CHECK(finite(m.worldToCamera) && finite(m.worldToScreen));
    // What was accepted writes back to the same bytes (the values are copied bit for bit).
    rtd::writeMatrixFile(copy, m);
    std::ifstream in(copy, std::ios::binary);
    const std::string written((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
    RTD_FUZZ_CHECK(written.size() == size && std::memcmp(written.data(), data, size) == 0);
    return 0;
}
