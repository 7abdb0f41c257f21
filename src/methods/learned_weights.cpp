#include "methods/learned_weights.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "rtdenoise/error.h"

namespace rtd {
namespace {

constexpr std::string_view kMagic = "rtdenoise-weights 2";
// Format 1 did not record the margin of the range its network was trained for (margin 1 until
// 2026-12-07): such a network would run silently on another range.
constexpr std::string_view kFormat1 = "rtdenoise-weights 1";
constexpr std::string_view kChecksumKey = "fnv1a32 ";

[[noreturn]] void refuse(const std::string& source, const std::string& problem) {
    throw Error(ErrorCode::InvalidInput,
                source + ": not a learned-method weights file: " + problem);
}

// The whitespace-separated words of `text`, with the line each starts on.
struct Word {
    std::string_view text;
    int line;
};
std::vector<Word> words(std::string_view text) {
    std::vector<Word> out;
    int line = 1;
    std::size_t i = 0;
    while (i < text.size()) {
        const char c = text[i];
        if (c == '\n') ++line;
        if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
            ++i;
            continue;
        }
        std::size_t end = i;
        while (end < text.size() && text[end] != ' ' && text[end] != '\t' && text[end] != '\r' &&
               text[end] != '\n')
            ++end;
        out.push_back({text.substr(i, end - i), line});
        i = end;
    }
    return out;
}

}  // namespace

std::uint32_t learnedWeightsChecksum(std::string_view body) {
    std::uint32_t hash = 2166136261u;
    for (unsigned char c : body) {
        hash ^= c;
        hash *= 16777619u;
    }
    return hash;
}

LearnedNetwork parseLearnedWeights(std::string_view text, const std::string& source) {
    if (text.substr(0, kFormat1.size()) == kFormat1 &&
        (text.size() == kFormat1.size() || text[kFormat1.size()] == '\n' ||
         text[kFormat1.size()] == '\r'))
        refuse(source, fmt::format("it is format 1, which does not record the range its network "
                                   "was trained for; this build reads '{}' (retrain it: "
                                   "training/README.md)",
                                   kMagic));
    if (text.substr(0, kMagic.size()) != kMagic)
        refuse(source, fmt::format("the first line is not '{}'", kMagic));
    // The checksum line covers every byte before it: a truncated or edited file fails here.
    const std::size_t checksumAt = text.rfind(std::string("\n") + std::string(kChecksumKey));
    if (checksumAt == std::string_view::npos)
        refuse(source, "no 'fnv1a32' line at its end (a truncated file?)");
    const std::string_view body = text.substr(0, checksumAt + 1);
    std::string_view stated = text.substr(checksumAt + 1 + kChecksumKey.size());
    while (!stated.empty() &&
           (stated.back() == '\n' || stated.back() == '\r' || stated.back() == ' '))
        stated.remove_suffix(1);
    std::uint32_t expected = 0;
    const auto [end, error] =
        std::from_chars(stated.data(), stated.data() + stated.size(), expected, 16);
    if (error != std::errc() || end != stated.data() + stated.size() || stated.size() != 8)
        refuse(source, fmt::format("the checksum '{}' is not 8 hex digits", stated));
    const std::uint32_t actual = learnedWeightsChecksum(body);
    if (actual != expected)
        refuse(source, fmt::format("its checksum is {:08x}, the file says {:08x} (truncated or "
                                   "edited since it was written)",
                                   actual, expected));

    // Line 2: the network and its shape, which must be this library's.
    const std::size_t secondLine = body.find('\n') + 1;
    const std::size_t secondEnd = body.find('\n', secondLine);
    const std::string_view shape = body.substr(secondLine, secondEnd - secondLine);
    const std::string wanted = fmt::format("network learned-mix {} {} {} {}", kLearnedFeatures,
                                           kLearnedHidden, kLearnedHidden, kLearnedCandidates);
    if (shape != wanted)
        refuse(source, fmt::format("line 2 is '{}'; this build reads '{}'", shape, wanted));
    // Line 3: the range the network was trained for (kernels/learned.h learnedRangeEnd).
    const std::size_t thirdEnd = body.find('\n', secondEnd + 1);
    const std::string_view range = thirdEnd == std::string_view::npos
                                       ? std::string_view()
                                       : body.substr(secondEnd + 1, thirdEnd - secondEnd - 1);
    const std::string wantedRange = fmt::format("range l0-margin {:g}", kLearnedL0NoiseMargin);
    if (range != wantedRange)
        refuse(source, fmt::format("line 3 is '{}'; this build's range is '{}' (a network "
                                   "trained for another range: retrain it)",
                                   range, wantedRange));
    const std::size_t fourthEnd = body.find('\n', thirdEnd + 1);
    if (fourthEnd == std::string_view::npos || body.substr(thirdEnd + 1, 8) != "trained ")
        refuse(source, "line 4 is not 'trained <how>'");

    LearnedNetwork n{};
    struct Block {
        const char* name;
        float* values;
        int count;
    };
    const Block blocks[] = {
        {"w1", &n.w1[0][0], kLearnedHidden * kLearnedFeatures},   {"b1", n.b1, kLearnedHidden},
        {"w2", &n.w2[0][0], kLearnedHidden * kLearnedHidden},     {"b2", n.b2, kLearnedHidden},
        {"w3", &n.w3[0][0], kLearnedCandidates * kLearnedHidden}, {"b3", n.b3, kLearnedCandidates},
    };
    const std::vector<Word> all = words(body.substr(fourthEnd + 1));
    std::size_t w = 0;
    for (const Block& b : blocks) {
        if (w >= all.size() || all[w].text != b.name)
            refuse(source, fmt::format("expected the block '{}'{}", b.name,
                                       w < all.size() ? fmt::format(" where '{}' is", all[w].text)
                                                      : std::string(" before the end")));
        ++w;
        for (int i = 0; i < b.count; ++i, ++w) {
            if (w >= all.size() || (all[w].text[0] >= 'a' && all[w].text[0] <= 'z' &&
                                    all[w].text != "inf" && all[w].text != "nan"))
                refuse(source, fmt::format("block '{}' has {} values, not {}", b.name, i, b.count));
            // from_chars: the same reading in every locale (strtof would take "0,5" in some).
            // Read as a double: a float's overflow is then refused, its underflow kept (a
            // denormal or 0).
            const std::string_view word = all[w].text;
            double v = 0.0;
            const auto parsed = std::from_chars(word.data(), word.data() + word.size(), v);
            if (parsed.ptr != word.data() + word.size() || parsed.ec != std::errc() ||
                !std::isfinite(v) || std::fabs(v) > double(std::numeric_limits<float>::max()))
                refuse(source,
                       fmt::format("'{}' in block '{}' is not a finite number", word, b.name));
            b.values[i] = float(v);
        }
    }
    if (w != all.size()) refuse(source, fmt::format("'{}' after the last block", all[w].text));
    return n;
}

LearnedNetwork learnedNetwork(const std::string& file) {
    if (file.empty()) {
        static const LearnedNetwork builtIn =
            parseLearnedWeights(builtInLearnedWeights(), "the built-in weights");
        return builtIn;
    }
    std::error_code ec;
    if (!std::filesystem::exists(file, ec))
        throw Error(ErrorCode::MissingFile, file + ": no such weights file");
    if (!std::filesystem::is_regular_file(file, ec))
        throw Error(ErrorCode::InvalidInput, file + ": not a regular file (a weights file)");
    std::ifstream in(file, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    if (!in && !in.eof())
        throw Error(ErrorCode::IoFailure, file + ": cannot read the weights file");
    return parseLearnedWeights(text.str(), file);
}

}  // namespace rtd
