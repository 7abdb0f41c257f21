// Private to the I/O layer: the direct reader of plain scan-line EXR files that readExr tries
// before OpenEXR's own, the direct writer of uncompressed ones, and the parts of them the tests
// check alone.
#pragma once

#include <ImfForward.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "rtdenoise/image.h"

namespace rtd::io_detail {

// A header's size is checked before anything is allocated for it: a corrupt or hostile header
// would otherwise end in std::bad_alloc or an allocation of gigabytes.
inline constexpr std::int64_t kMaxSide = 65536;
inline constexpr std::int64_t kMaxPixels = std::int64_t(1) << 28;  // 16384 x 16384
// OpenEXR allocates each (de)compression buffer at one block's claimed size, pixels of every
// channel: a tile of 65536x65536, or a scan-line block of thousands of channels, from a file of
// a few hundred bytes (fuzz_exr: malloc(1811939352)). 256 MB holds a 16384-wide block of 256
// lines (DWAB's) of 4 float channels four times over.
inline constexpr std::int64_t kMaxBlockBytes = std::int64_t(1) << 28;

// Reads the channels of `channelChoices` (first match wins, as readExr) from a single-part
// scan-line EXR stored uncompressed, as zips or as zip, with unsampled HALF, FLOAT or UINT
// channels: the blocks are inflated and converted on OpenEXR's thread pool (setExrThreads), by
// libdeflate where it was found at build time, and copied without OpenEXR's value-by-value
// conversion. The values are the ones OpenEXR reads. Returns nothing for a file of any other
// kind and for anything unexpected (a block's size, position or content): readExr then reads
// it with OpenEXR, which reports what is wrong.
std::optional<Image> readExrBlocks(const std::filesystem::path& file,
                                   const std::vector<std::vector<std::string>>& channelChoices);

// readExr without the direct reader: OpenEXR alone (the tests compare the two).
Image readExrWithOpenExr(const std::filesystem::path& file,
                         const std::vector<std::vector<std::string>>& channelChoices);

// The bytes of an uncompressed single-part scan-line EXR of `image` with `header` (its channels
// and data window, of image's size): what OpenEXR writes, byte for byte. Image channel c goes to
// the header's channel channelNames[c], FLOAT or HALF (rounded to nearest even). OpenEXR's writer
// hands every line, a block of its own, to its thread pool and waits for it: 512 hand-offs for a
// 512-line image, longer than the copy.
std::string uncompressedExrBytes(const Imf::Header& header, const Image& image,
                                 const std::vector<std::string>& channelNames);

// ZIP's byte transforms, undone: t[i] += t[i-1] - 128 over the block (a running sum), then the
// block's first and second halves interleaved byte by byte into `out`.
void undoZipPredictor(unsigned char* bytes, std::size_t count);
void interleaveHalves(const unsigned char* bytes, std::size_t count, unsigned char* out);

}  // namespace rtd::io_detail
