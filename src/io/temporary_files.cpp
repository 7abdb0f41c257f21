// The registry of live temporary files and ffmpeg children (atomic_file.h) and the clean-up a
// program's SIGINT/SIGTERM handler calls: an interrupted run leaves no ".x.tmp-PID-N" behind and
// no ffmpeg still writing.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "io/atomic_file.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace io_detail {
namespace {

// Writer threads plus the video and its log: far fewer than this are live at once.
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;

enum SlotState : int { kFree = 0, kFilling = 1, kLive = 2 };

struct Slot {
    std::atomic<int> state{kFree};
    char path[kPathBytes];
};

Slot temporaries[kSlots];
std::atomic<pid_t> children[4];
std::atomic<int> spawning{0};  // children being started, not registered yet
// Files being created by path, and whether the clean-up has begun. Both sequentially consistent:
// a writer that finds `abandoning` false is seen in `creating` by the clean-up, which waits.
std::atomic<int> creating{0};
std::atomic<bool> abandoning{false};

static_assert(std::atomic<int>::is_always_lock_free && std::atomic<pid_t>::is_always_lock_free,
              "the signal handler reads the registry: its atomics must not take locks");

}  // namespace

int registerTemporary(const std::filesystem::path& path) noexcept {
    const std::string& text = path.native();
    if (text.size() >= kPathBytes) return -1;
    for (int i = 0; i < kSlots; ++i) {
        int expected = kFree;
        if (!temporaries[i].state.compare_exchange_strong(expected, kFilling)) continue;
        std::memcpy(temporaries[i].path, text.c_str(), text.size() + 1);
        temporaries[i].state.store(kLive);  // only now may the handler read the path
        return i;
    }
    return -1;
}

void unregisterTemporary(int slot) noexcept {
    if (slot >= 0 && slot < kSlots) temporaries[slot].state.store(kFree);
}

void registerChild(pid_t child) noexcept {
    for (auto& entry : children) {
        pid_t expected = 0;
        if (entry.compare_exchange_strong(expected, child)) return;
    }
}

void unregisterChild(pid_t child) noexcept {
    for (auto& entry : children) {
        pid_t expected = child;
        entry.compare_exchange_strong(expected, 0);
    }
}

void beginChildSpawn() noexcept {
    spawning.fetch_add(1);
}

void endChildSpawn() noexcept {
    spawning.fetch_sub(1);
}

FileCreation::FileCreation(const std::filesystem::path& file) {
    creating.fetch_add(1);
    if (abandoning.load()) {
        creating.fetch_sub(1);
        active_ = false;
        throw Error(ErrorCode::IoFailure, file.string() + ": not written: the run is interrupted");
    }
}

void FileCreation::finish() noexcept {
    if (active_) creating.fetch_sub(1);
    active_ = false;
}

void allowCreationAgain() noexcept {
    abandoning.store(false);
}

void removeLiveTemporaries() noexcept {
    abandoning.store(true);
    const timespec millisecond{0, 1000000};
    // A writer between its check and its file's creation: wait for the file, then unlink it.
    for (int wait = 0; creating.load() > 0 && wait < 1000; ++wait)
        ::nanosleep(&millisecond, nullptr);
    // A child being started is registered within microseconds by a thread that has these signals
    // blocked (so it is not this one): wait for it, up to a second, rather than leave it running.
    for (int wait = 0; spawning.load() > 0 && wait < 1000; ++wait)
        ::nanosleep(&millisecond, nullptr);
    // The children first: a killed ffmpeg writes no more into the file about to be unlinked.
    for (auto& entry : children) {
        const pid_t child = entry.exchange(0);
        if (child <= 0) continue;
        ::kill(child, SIGKILL);
        while (::waitpid(child, nullptr, 0) == -1 && errno == EINTR) {
        }
    }
    for (Slot& slot : temporaries)
        if (slot.state.load() == kLive) ::unlink(slot.path);
}

}  // namespace io_detail

void abandonTemporaryFiles() noexcept {
    io_detail::removeLiveTemporaries();
}

}  // namespace rtd
