// Private helpers of the I/O layer: temporary names beside the target and the rename that
// publishes them, so a reader never sees a half-written file.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <system_error>

#include "rtdenoise/error.h"

namespace rtd::io_detail {

// Throws IoFailure when the folder `file` goes into is missing, with a clearer message than the
// "No such file" a writer would report for the temporary name.
inline void requireParentFolder(const std::filesystem::path& file) {
    const std::filesystem::path parent = file.parent_path();
    if (parent.empty()) return;  // the current folder
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(parent, ec);
    if (std::filesystem::is_directory(status)) return;
    throw Error(ErrorCode::IoFailure,
                file.string() + ": cannot write, '" + parent.string() +
                    (std::filesystem::exists(status) ? "' is not a folder" : "' does not exist"));
}

// The process-wide list of the temporary files being written and of the ffmpeg children, kept
// so that removeLiveTemporaries() can clean up from a signal handler: fixed slots holding
// C strings copied in advance, so the handler needs no allocation and no lock.
// Returns the slot to pass to unregisterTemporary, or -1 when the path is not tracked (all slots
// busy, or a path too long), in which case only the writer's own clean-up removes it.
int registerTemporary(const std::filesystem::path& path) noexcept;
void unregisterTemporary(int slot) noexcept;
void registerChild(pid_t child) noexcept;
void unregisterChild(pid_t child) noexcept;
// Around starting a child and registering it, with SIGINT/SIGTERM blocked in that thread: the
// clean-up then waits for the registration instead of missing a child started a moment ago.
void beginChildSpawn() noexcept;
void endChildSpawn() noexcept;
// Kills and reaps the registered children, then unlinks the registered files. Async-signal-safe.
// Files being created (FileCreation below) are waited for first, up to a second.
void removeLiveTemporaries() noexcept;
// Lets files be created again after removeLiveTemporaries: for a test that abandons and goes on
// in the same process (a program exits after abandoning).
void allowCreationAgain() noexcept;

// Held around the call that creates a registered temporary by its path (fopen, OpenEXR's
// OutputFile): without it, the clean-up could unlink the path just before the writer creates it,
// leaving the file behind. Once the clean-up has begun, construction throws IoFailure instead of
// letting a file be created.
class FileCreation {
  public:
    // file: the file the caller asked for (not its temporary), which the error names.
    explicit FileCreation(const std::filesystem::path& file);
    ~FileCreation() { finish(); }
    FileCreation(const FileCreation&) = delete;
    FileCreation& operator=(const FileCreation&) = delete;
    // The file exists (or its creation failed): the clean-up may go on.
    void finish() noexcept;

  private:
    bool active_ = true;
};

// Throws MissingFile for a missing file or a dangling link, InvalidInput for a folder or other
// non-regular file ("is a folder, not <kind>"), each naming the file.
inline void requireRegularFile(const std::filesystem::path& file, const char* kind) {
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(file, ec);
    if (!std::filesystem::exists(status)) {
        const bool dangling =
            std::filesystem::is_symlink(std::filesystem::symlink_status(file, ec));
        throw Error(ErrorCode::MissingFile,
                    file.string() +
                        (dangling ? ": a link to a file that does not exist" : ": no such file"));
    }
    if (!std::filesystem::is_regular_file(status)) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + (std::filesystem::is_directory(status)
                                         ? std::string(": is a folder, not ") + kind
                                         : std::string(": not a regular file")));
    }
}

// ".<name>.tmp-<pid>-<n>" in the same folder: the same file system, so the rename is atomic; the
// counter keeps two threads of one process writing the same name apart.
inline std::filesystem::path temporaryPathFor(const std::filesystem::path& file) {
    static std::atomic<unsigned> counter{0};
    // Appended piecewise: "literal" + std::string&& trips GCC 12's -Wrestrict false positive.
    std::string name = ".";
    name += file.filename().string();
    name += ".tmp-";
    name += std::to_string(::getpid());
    name += "-";
    name += std::to_string(counter.fetch_add(1));
    return file.parent_path() / name;
}

// Removes the temporary file on scope exit unless the write was committed.
class TemporaryFile {
  public:
    explicit TemporaryFile(std::filesystem::path path)
        : path_(std::move(path)), registration_(registerTemporary(path_)) {}
    ~TemporaryFile() {
        if (!committed_) {
            std::error_code ec;
            std::filesystem::remove(path_, ec);
        }
        unregisterTemporary(registration_);
    }
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

    const std::filesystem::path& path() const { return path_; }

    // Renames the temporary file to `file`; throws IoFailure naming `file` if that fails.
    void commitTo(const std::filesystem::path& file) {
        std::error_code ec;
        std::filesystem::rename(path_, file, ec);
        if (ec) {
            throw Error(
                ErrorCode::IoFailure,
                file.string() + ": cannot move the finished file into place: " + ec.message());
        }
        committed_ = true;
    }

  private:
    std::filesystem::path path_;
    int registration_;  // registered before the file exists, so an interrupt never misses it
    bool committed_ = false;
};

}  // namespace rtd::io_detail
