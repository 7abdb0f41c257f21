// The error boundary of the library: every failure is an rtd::Error with a code and a message
// that names the file (or the argument) and the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace rtd {

enum class ErrorCode {
    InvalidArgument,  // a setting or an argument out of its range
    MissingFile,      // a file the layout requires is not there
    InvalidInput,     // a file is there but its content is wrong (channels, sizes, IDs, .mat)
    IoFailure,        // reading or writing failed (truncated file, unwritable folder)
    MissingTool,      // an external program (ffmpeg) is not installed
    DeviceFailure,    // the compute device failed or is absent
    OutOfMemory,      // an allocation on the device (host memory for the CPU) failed
};

class Error : public std::runtime_error {
  public:
    Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
    ErrorCode code() const noexcept { return code_; }

  private:
    ErrorCode code_;
};

}  // namespace rtd
