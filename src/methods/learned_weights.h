// The learned method's weights files (docs/learned_spec.md): the built-in one compiled in
// (weights/learned.txt), or a user's, checked before use.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "kernels/learned.h"

namespace rtd {

// Parses a weights file's text; `source` names it in errors (rtd::Error InvalidInput: a wrong
// header or shape, a missing or unreadable number, a truncated file, a checksum that differs).
LearnedNetwork parseLearnedWeights(std::string_view text, const std::string& source);
// The network of `file`, or the built-in one where `file` is empty. Throws rtd::Error
// (MissingFile, InvalidInput) naming the file.
LearnedNetwork learnedNetwork(const std::string& file);
// A weights file's checksum (its `fnv1a32` line): FNV-1a, 32 bits, of every byte before that line.
std::uint32_t learnedWeightsChecksum(std::string_view body);
// The built-in weights file's text.
std::string_view builtInLearnedWeights();

}  // namespace rtd
