// Private helper of the I/O layer shared by the readers of numbered frame files.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace rtd::io_detail {

// "0..6 and 8..19" for sorted, distinct numbers (the first few ranges, then "...").
std::string describeRanges(const std::vector<int>& sorted);

// Only regular files, or links to them, are frames; anything else of a frame's name is an error
// naming it (MissingFile: a dangling link; InvalidInput: a folder or other non-regular file),
// not a frame whose other files then seem to be missing.
void requireFrameFile(const std::filesystem::directory_entry& entry);

}  // namespace rtd::io_detail
