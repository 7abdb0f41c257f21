// Sizes of strided images with every product and sum checked: a caller's stride of 2^63 must be
// refused, not wrap around into a small span that passes the "large enough" tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

namespace rtd {

// a * b, or nullopt where it overflows.
inline std::optional<std::size_t> checkedProduct(std::size_t a, std::size_t b) {
    std::size_t product = 0;
    if (__builtin_mul_overflow(a, b, &product)) return std::nullopt;
    return product;
}

// Bytes from a width x height image's first value to its last one's end, or nullopt where that
// overflows or exceeds PTRDIFF_MAX (the kernels' strides are signed 64-bit offsets).
inline std::optional<std::size_t> imageSpanBytes(std::size_t width, std::size_t height,
                                                 std::size_t pixelStride, std::size_t rowStride,
                                                 std::size_t pixelBytes) {
    if (width == 0 || height == 0) return std::size_t(0);
    std::size_t lastColumn = 0, lastRow = 0, span = 0;
    if (__builtin_mul_overflow(width - 1, pixelStride, &lastColumn) ||
        __builtin_mul_overflow(height - 1, rowStride, &lastRow) ||
        __builtin_add_overflow(lastColumn, lastRow, &span) ||
        __builtin_add_overflow(span, pixelBytes, &span) || span > std::size_t(PTRDIFF_MAX) ||
        pixelStride > std::size_t(PTRDIFF_MAX) || rowStride > std::size_t(PTRDIFF_MAX))
        return std::nullopt;
    return span;
}

// Whether [data, data + bytes) lies within the address space (does not wrap past its end).
inline bool fitsAddressSpace(const void* data, std::size_t bytes) {
    return reinterpret_cast<std::uintptr_t>(data) <= UINTPTR_MAX - bytes;
}

}  // namespace rtd
