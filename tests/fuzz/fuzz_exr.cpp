// libFuzzer target: rtd::readExrSize and rtd::readExr on arbitrary bytes, with the channel
// choices Sequence uses (RGB; depth's and ID's scalar names) and an output channel repeated.
// An rtd::Error is the expected outcome of a bad file; a crash, a leak, undefined behaviour, an
// allocation over -malloc_limit_mb, any other exception, or a result that disagrees with the
// header check (readExrSize) is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace {

using Choices = std::vector<std::vector<std::string>>;
const Choices kChoices[] = {
    {{"R"}, {"G"}, {"B"}},
    {{"Y", "Z", "R", "depth.Y", "depth.Z"}},
    {{"Y", "R", "ID.Y", "id.Y"}},
    {{"R"}, {"R"}, {"G"}},  // a channel read twice: copied after the read
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::filesystem::path file = rtd::fuzz::scratchFolder("exr") / "input.exr";
    rtd::fuzz::writeBytes(file, data, size);
    // The last byte picks the channel choices, so that every set sees every input's structure.
    const Choices& choices = kChoices[size > 0 ? data[size - 1] % 4 : 0];
    bool headerOk = false;
    rtd::ExrSize header;
    try {
        header = rtd::readExrSize(file, choices);
        headerOk = true;
        RTD_FUZZ_CHECK(header.width > 0 && header.height > 0);
    } catch (const rtd::Error&) {
    }
    try {
        const rtd::Image image = rtd::readExr(file, choices);
        // readExr makes every check readExrSize makes, so it cannot accept what that refused.
        RTD_FUZZ_CHECK(headerOk);
        RTD_FUZZ_CHECK(image.width == header.width && image.height == header.height);
        RTD_FUZZ_CHECK(image.channels == int(choices.size()));
        RTD_FUZZ_CHECK(image.pixels.size() == image.pixelCount() * std::size_t(image.channels));
        volatile float sum = 0.0f;  // every value read (ASan sees an uninitialised read as none)
        for (float v : image.pixels) sum = sum + (std::isnan(v) ? 0.0f : 1.0f);
    } catch (const rtd::Error&) {
    }
    return 0;
}
