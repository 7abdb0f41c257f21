// PNG writing with libpng, encoded in memory and published with writeFileAtomically.
#include <fmt/format.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

// State shared with libpng's C callbacks. libpng reports errors by longjmp, so everything the
// jump can skip is plain data: no destructor runs between setjmp and png_write_end.
struct PngContext {
    std::string* output = nullptr;
    bool outOfMemory = false;
    char message[256] = {};
};

void onPngError(png_structp png, png_const_charp message) {
    auto* context = static_cast<PngContext*>(png_get_error_ptr(png));
    std::snprintf(context->message, sizeof(context->message), "%s", message);
    png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp) {}

void onPngWrite(png_structp png, png_bytep data, png_size_t length) {
    auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
    try {
        context->output->append(reinterpret_cast<const char*>(data), length);
    } catch (...) {
        context->outOfMemory = true;
    }
    // Outside the catch block: png_error leaves by longjmp.
    if (context->outOfMemory) png_error(png, "out of memory");
}

void onPngFlush(png_structp) {}

// Returns false on failure with libpng's message in context.message. The context lives in the
// caller so that its changes survive the longjmp (locals of this function would not reliably).
bool encodeRgb8(const unsigned char* pixels, int width, int height, PngContext& context) {
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, onPngError, onPngWarning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    png_set_write_fn(png, &context, onPngWrite, onPngFlush);
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    const std::size_t rowBytes = std::size_t(width) * 3;
    for (int y = 0; y < height; ++y) {
        png_write_row(png, const_cast<png_bytep>(pixels + rowBytes * y));
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return true;
}

unsigned char toByte(float value) {
    if (!(value > 0.0f)) return 0;  // also NaN
    if (value >= 1.0f) return 255;
    return static_cast<unsigned char>(std::lround(value * 255.0f));
}

}  // namespace

void writePng(const std::filesystem::path& file, const Image& image) {
    if (image.channels != 3 && image.channels != 1) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writePng needs a 1- or 3-channel image, got " +
                        std::to_string(image.channels) + " channels");
    }
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != image.pixelCount() * image.channels) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writePng got an empty or inconsistent image (" +
                        std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    }
    std::vector<unsigned char> bytes(image.pixelCount() * 3);
    for (std::size_t i = 0; i < image.pixelCount(); ++i) {
        for (int c = 0; c < 3; ++c) {
            bytes[i * 3 + c] =
                toByte(image.pixels[i * image.channels + (image.channels == 3 ? c : 0)]);
        }
    }
    std::string encoded;
    PngContext context;
    context.output = &encoded;
    if (!encodeRgb8(bytes.data(), image.width, image.height, context)) {
        throw Error(ErrorCode::IoFailure,
                    file.string() + ": cannot encode PNG: " +
                        (context.message[0] ? context.message : "libpng failed"));
    }
    writeFileAtomically(file, encoded);
}

void writeFileAtomically(const std::filesystem::path& file, const std::string& bytes) {
    io_detail::requireParentFolder(file);
    io_detail::TemporaryFile temporary(io_detail::temporaryPathFor(file));
    const auto fail = [&](int error) {
        throw Error(ErrorCode::IoFailure,
                    file.string() + ": cannot write: " + std::strerror(error));
    };
    io_detail::FileCreation creation(file);
    std::FILE* out = std::fopen(temporary.path().c_str(), "wb");
    creation.finish();
    if (!out) fail(errno);
    const bool written = std::fwrite(bytes.data(), 1, bytes.size(), out) == bytes.size();
    const int writeError = errno;
    // fclose flushes, so its result is part of whether the write worked.
    const bool closed = std::fclose(out) == 0;
    if (!written) fail(writeError);
    if (!closed) fail(errno);
    temporary.commitTo(file);
}

void checkOutputFolder(const std::filesystem::path& folder) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(folder, ec);
    if (fs::exists(status)) {
        if (!fs::is_directory(status))
            throw Error(ErrorCode::IoFailure,
                        fmt::format("{}: cannot be the output folder: it is a file, not a folder",
                                    folder.string()));
        if (::access(folder.c_str(), W_OK | X_OK) != 0)
            throw Error(ErrorCode::IoFailure,
                        fmt::format("{}: the output folder is not writable", folder.string()));
        return;
    }
    // It will be created: the nearest existing folder above it must be a writable folder.
    fs::path existing = fs::absolute(folder, ec).lexically_normal();
    while (existing.has_relative_path() && !fs::exists(fs::status(existing, ec)))
        existing = existing.parent_path();
    if (!fs::is_directory(fs::status(existing, ec)))
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: cannot create the output folder: '{}' is a file, not a folder",
                                folder.string(), existing.string()));
    if (::access(existing.c_str(), W_OK | X_OK) != 0)
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: cannot create the output folder: '{}' is not writable",
                                folder.string(), existing.string()));
}

void checkOutputFile(const std::filesystem::path& file) {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec))
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: cannot write, it is a folder", file.string()));
    io_detail::requireParentFolder(file);
    const std::filesystem::path parent = file.parent_path();
    if (::access(parent.empty() ? "." : parent.c_str(), W_OK | X_OK) != 0)
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: cannot write, folder '{}' is not writable", file.string(),
                                parent.string()));
}

void prepareOutputFolder(const std::filesystem::path& folder) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec || !std::filesystem::is_directory(folder))
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: cannot create the output folder ({})", folder.string(),
                                ec ? ec.message() : "not a directory"));
    // Probe with a real file: permissions, read-only mounts and full disks all show here.
    std::filesystem::path probe = folder / ".rtdenoise-write-test";
    try {
        writeFileAtomically(probe, "");
    } catch (const Error&) {
        throw Error(ErrorCode::IoFailure,
                    fmt::format("{}: the output folder is not writable", folder.string()));
    }
    std::filesystem::remove(probe, ec);
}

}  // namespace rtd
