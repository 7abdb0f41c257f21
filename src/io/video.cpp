// MP4 output through the ffmpeg program: raw rgb24 frames down a pipe to a spawned ffmpeg (its
// pid known, so an interrupt can stop it), ffmpeg's messages kept in a log beside the temporary
// file so a failure can say what went wrong.
#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

// A write to a pipe whose reader died raises SIGPIPE, which kills the process by default. A
// library must not change the process's signal handling, so the signal is blocked for this
// thread around pipe operations and a SIGPIPE they raised is consumed before unblocking.
class SigpipeBlock {
  public:
    SigpipeBlock() {
        sigemptyset(&set_);
        sigaddset(&set_, SIGPIPE);
        sigset_t pending;
        sigemptyset(&pending);
        sigpending(&pending);
        wasPending_ = sigismember(&pending, SIGPIPE) == 1;
        pthread_sigmask(SIG_BLOCK, &set_, &previous_);
    }
    ~SigpipeBlock() {
        if (!wasPending_) {
            const timespec zero{0, 0};
            sigtimedwait(&set_, nullptr, &zero);
        }
        pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
    }
    SigpipeBlock(const SigpipeBlock&) = delete;
    SigpipeBlock& operator=(const SigpipeBlock&) = delete;

  private:
    sigset_t set_;
    sigset_t previous_;
    bool wasPending_ = false;
};

std::filesystem::path logPathFor(const std::filesystem::path& tempFile) {
    return std::filesystem::path(tempFile.string() + ".log");
}

// The end of ffmpeg's log, on one line, for an error message.
std::string logTail(const std::filesystem::path& log) {
    std::ifstream in(log);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::replace(text.begin(), text.end(), '\n', ' ');
    while (!text.empty() && (text.back() == ' ' || text.back() == '\r')) text.pop_back();
    constexpr std::size_t kMax = 600;
    if (text.size() > kMax) text = "..." + text.substr(text.size() - kMax);
    return text;
}

// Closes the pipe, waiting for ffmpeg; returns its exit code, or -1 if it did not exit normally.
int closePipe(void* pipe, int child) {
    SigpipeBlock block;
    std::fclose(static_cast<std::FILE*>(pipe));
    int status = 0;
    pid_t waited;
    while ((waited = ::waitpid(child, &status, 0)) == -1 && errno == EINTR) {
    }
    io_detail::unregisterChild(child);
    if (waited == -1 || !WIFEXITED(status)) return -1;
    return WEXITSTATUS(status);
}

// Starts `arguments` (found on PATH) with its standard input reading from the returned FILE* and
// its standard error into `log`; throws IoFailure naming `file` if it cannot be started.
std::FILE* spawnWithPipe(const std::vector<std::string>& arguments,
                         const std::filesystem::path& log, const std::filesystem::path& file,
                         pid_t& child) {
    int ends[2];
    // Close-on-exec: the child gets the read end as its stdin only, no copy of the write end
    // (which would keep it from ever seeing the end of its input).
    if (::pipe2(ends, O_CLOEXEC) != 0)
        throw Error(ErrorCode::IoFailure,
                    file.string() + ": cannot start ffmpeg: " + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, ends[0], STDIN_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    for (const std::string& argument : arguments)
        argv.push_back(const_cast<char*>(argument.c_str()));
    argv.push_back(nullptr);
    // An interrupt between the start and the registration would miss the child: this thread
    // takes none meanwhile, and the clean-up in another one waits for the registration.
    sigset_t interrupts, previous;
    sigemptyset(&interrupts);
    sigaddset(&interrupts, SIGINT);
    sigaddset(&interrupts, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &interrupts, &previous);
    io_detail::beginChildSpawn();
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setsigmask(&attributes, &previous);  // the child takes signals as we did
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
    std::fflush(nullptr);  // nothing buffered twice
    const int failed = ::posix_spawnp(&child, argv[0], &actions, &attributes, argv.data(), environ);
    if (failed == 0) io_detail::registerChild(child);
    io_detail::endChildSpawn();
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    ::close(ends[0]);
    if (failed != 0) {
        ::close(ends[1]);
        throw Error(ErrorCode::IoFailure,
                    file.string() + ": cannot start ffmpeg: " + std::strerror(failed));
    }
    std::FILE* pipe = ::fdopen(ends[1], "w");
    if (!pipe) {
        ::close(ends[1]);
        int status = 0;
        ::waitpid(child, &status, 0);
        io_detail::unregisterChild(child);
        throw Error(ErrorCode::IoFailure,
                    file.string() + ": cannot start ffmpeg: " + std::strerror(errno));
    }
    return pipe;
}

void removeQuietly(const std::filesystem::path& file) {
    std::error_code ec;
    std::filesystem::remove(file, ec);
}

}  // namespace

bool VideoWriter::ffmpegAvailable() {
    const char* path = std::getenv("PATH");
    if (!path) return false;
    std::string_view rest(path);
    while (true) {
        const std::size_t colon = rest.find(':');
        const std::string_view entry = rest.substr(0, colon);
        // An empty PATH entry means the current folder, as it does for sh.
        const std::filesystem::path candidate =
            std::filesystem::path(entry.empty() ? "." : std::string(entry)) / "ffmpeg";
        std::error_code ec;
        if (std::filesystem::is_regular_file(candidate, ec) &&
            ::access(candidate.c_str(), X_OK) == 0) {
            return true;
        }
        if (colon == std::string_view::npos) return false;
        rest.remove_prefix(colon + 1);
    }
}

VideoWriter::VideoWriter(std::filesystem::path file, int width, int height, int framesPerSecond)
    : file_(std::move(file)), width_(width), height_(height) {
    if (width <= 0 || height <= 0 || framesPerSecond <= 0) {
        throw Error(ErrorCode::InvalidArgument,
                    file_.string() + ": video size and frame rate must be positive, got " +
                        std::to_string(width) + "x" + std::to_string(height) + " at " +
                        std::to_string(framesPerSecond) + " fps");
    }
    if (!ffmpegAvailable()) {
        throw Error(
            ErrorCode::MissingTool,
            "ffmpeg not found on PATH: install it (apt-get install ffmpeg) or drop --video");
    }
    io_detail::requireParentFolder(file_);
    tempFile_ = io_detail::temporaryPathFor(file_);

    // Absolute paths: a relative name starting with '-' would read as an ffmpeg option.
    std::error_code ec;
    const std::filesystem::path absolute = std::filesystem::absolute(tempFile_, ec);
    const std::filesystem::path output = ec ? tempFile_ : absolute;
    // Registered before ffmpeg creates them: an interrupt from here on removes both.
    tempRegistration_ = io_detail::registerTemporary(tempFile_);
    logRegistration_ = io_detail::registerTemporary(logPathFor(tempFile_));
    const std::vector<std::string> arguments = {
        "ffmpeg",       "-y",
        "-loglevel",    "error",
        "-f",           "rawvideo",
        "-pix_fmt",     "rgb24",
        "-s",           std::to_string(width) + "x" + std::to_string(height),
        "-r",           std::to_string(framesPerSecond),
        "-i",           "-",
        "-c:v",         "libx264",
        "-pix_fmt",     "yuv420p",
        "-vf",          "pad=ceil(iw/2)*2:ceil(ih/2)*2",
        "-crf",         "18",
        "-f",           "mp4",
        output.string()};
    pid_t child = 0;
    try {
        pipe_ = spawnWithPipe(arguments, logPathFor(output), file_, child);
    } catch (...) {
        removeQuietly(logPathFor(tempFile_));
        io_detail::unregisterTemporary(tempRegistration_);
        io_detail::unregisterTemporary(logRegistration_);
        throw;
    }
    childPid_ = child;
}

VideoWriter::~VideoWriter() {
    if (pipe_) {
        closePipe(pipe_, childPid_);
        removeQuietly(tempFile_);
        removeQuietly(logPathFor(tempFile_));
    }
    io_detail::unregisterTemporary(tempRegistration_);
    io_detail::unregisterTemporary(logRegistration_);
}

void VideoWriter::addFrame(const Image& displayImage) {
    if (!pipe_) {
        throw Error(ErrorCode::InvalidArgument,
                    file_.string() + ": addFrame on a video that is finished or failed");
    }
    if (displayImage.width != width_ || displayImage.height != height_ ||
        (displayImage.channels != 3 && displayImage.channels != 1) ||
        displayImage.pixels.size() != displayImage.pixelCount() * displayImage.channels) {
        throw Error(ErrorCode::InvalidArgument,
                    file_.string() + ": frame is " + std::to_string(displayImage.width) + "x" +
                        std::to_string(displayImage.height) + " with " +
                        std::to_string(displayImage.channels) + " channels, the video is " +
                        std::to_string(width_) + "x" + std::to_string(height_) + " RGB");
    }
    rowBuffer_.resize(std::size_t(width_) * 3);
    const int channels = displayImage.channels;
    bool written = true;
    {
        SigpipeBlock block;
        auto* out = static_cast<std::FILE*>(pipe_);
        for (int y = 0; y < height_ && written; ++y) {
            for (int x = 0; x < width_; ++x) {
                for (int c = 0; c < 3; ++c) {
                    const float v = displayImage.at(x, y, channels == 3 ? c : 0);
                    rowBuffer_[std::size_t(x) * 3 + c] =
                        !(v > 0.0f) ? 0
                        : v >= 1.0f ? 255
                                    : static_cast<unsigned char>(std::lround(v * 255.0f));
                }
            }
            written =
                std::fwrite(rowBuffer_.data(), 1, rowBuffer_.size(), out) == rowBuffer_.size();
        }
    }
    if (!written) {
        // ffmpeg has gone: collect its reason and give up on this video.
        const int code = closePipe(pipe_, childPid_);
        pipe_ = nullptr;
        const std::string reason = logTail(logPathFor(tempFile_));
        removeQuietly(tempFile_);
        removeQuietly(logPathFor(tempFile_));
        throw Error(ErrorCode::IoFailure,
                    file_.string() + ": ffmpeg stopped accepting frames (exit code " +
                        std::to_string(code) + ")" + (reason.empty() ? "" : ": " + reason));
    }
}

void VideoWriter::finish() {
    if (!pipe_) {
        throw Error(ErrorCode::InvalidArgument,
                    file_.string() + ": finish on a video that is finished or failed");
    }
    const bool anyFrames = !rowBuffer_.empty();
    const int code = closePipe(pipe_, childPid_);
    pipe_ = nullptr;
    io_detail::TemporaryFile temporary(tempFile_);
    const std::filesystem::path log = logPathFor(tempFile_);
    const std::string reason = logTail(log);
    removeQuietly(log);
    if (!anyFrames) {
        throw Error(ErrorCode::InvalidArgument, file_.string() + ": no frames were added");
    }
    if (code != 0) {
        throw Error(ErrorCode::IoFailure, file_.string() + ": ffmpeg failed (exit code " +
                                              std::to_string(code) + ")" +
                                              (reason.empty() ? "" : ": " + reason));
    }
    temporary.commitTo(file_);
}

}  // namespace rtd
