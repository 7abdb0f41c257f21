// Reading course-layout sequences and writing results. Every function throws rtd::Error with the
// file's path and the problem; writers write to a temporary name and rename, so no file is ever
// left half-written.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "rtdenoise/image.h"

namespace rtd {

// ---- reading ----

// Reads the named channels of an EXR (HALF or FLOAT, any compression OpenEXR reads) into an
// interleaved float image. Each entry of `channelChoices` lists acceptable names for one output
// channel, first match wins (e.g. {{"R"}, {"G"}, {"B"}} or {{"Y", "Z", "R"}}).
Image readExr(const std::filesystem::path& file,
              const std::vector<std::vector<std::string>>& channelChoices);

// What readExr would return, from the header alone (no pixels read): the image's size, after
// the checks readExr makes before reading (the file, the channels, a plausible size).
struct ExrSize {
    int width = 0;
    int height = 0;
};
ExrSize readExrSize(const std::filesystem::path& file,
                    const std::vector<std::vector<std::string>>& channelChoices);

// Reads matrix_i.mat: int32 K, then K + 2 row-major float32 4x4 matrices (little-endian).
struct MatrixFile {
    std::vector<Matrix4> objectToWorld;  // K
    Matrix4 worldToCamera;
    Matrix4 worldToScreen;
};
MatrixFile readMatrixFile(const std::filesystem::path& file);
void writeMatrixFile(const std::filesystem::path& file, const MatrixFile& matrices);

// The index i of a file named "<stem>_<i><extension>" (canonical decimal: no sign, no leading
// zeros), or -1 for any other name.
int frameIndexOf(const std::string& fileName, std::string_view stem,
                 std::string_view extension = ".exr");

// The number N of "<stem>_<i><extension>" files in `folder`, which must be numbered 0..N-1:
// throws MissingFile for a missing folder or no such file, InvalidInput naming the first
// missing file on a gap, or an entry of that name that is not a regular file (a folder, a
// dangling link).
int countFrames(const std::filesystem::path& folder, std::string_view stem,
                std::string_view extension = ".exr");

// Removes the regular files "<stem>_<i><extension>" of `folder` with i >= firstRemoved (0: all
// of them): outputs of an earlier run that this one does not rewrite. Nothing else is touched.
void removeNumberedFiles(const std::filesystem::path& folder, std::string_view stem,
                         std::string_view extension, int firstRemoved);

// A folder in the course layout: beauty_i.exr, normal_i.exr, position_i.exr, depth_i.exr,
// ID_i.exr, matrix_i.mat, optional albedo_i.exr, for i = 0..frameCount-1.
class Sequence {
  public:
    // Discovers the frame count from beauty_<i>.exr; throws if none, or on a gap in the numbering.
    explicit Sequence(std::filesystem::path folder);

    int frameCount() const { return frameCount_; }
    const std::filesystem::path& folder() const { return folder_; }

    // Reads and validates frame i: all buffers the same size, IDs in -1..K-1.
    Frame readFrame(int index) const;

    // Checks frames 0..count-1 as far as can be done without reading pixels, so that a long run
    // does not fail at frame i: every file present, EXR headers with the channels readFrame
    // reads, the buffers of a frame of one size, every matrix_i.mat read and validated. Returns
    // each frame's size. Only the IDs (pixel values) are left to readFrame.
    std::vector<ExrSize> checkFrames(int count) const;

  private:
    std::filesystem::path folder_;
    int frameCount_ = 0;
};

// ---- writing ----

// Writes frame `index` of `frame` in the course layout into `folder` (beauty, normal, position,
// depth, ID, matrix, and albedo when the frame has one): what Sequence reads back, the EXRs with
// writeExr's default options. Creates the folder if needed.
void writeFrame(const std::filesystem::path& folder, int index, const Frame& frame);

// The compressions OpenEXR 3.1 writes. Lossless: none, rle, zips, zip, piz; b44 and b44a too for
// FLOAT channels (they compress HALF ones only); pxr24 for HALF (FLOAT loses its 8 low mantissa
// bits). Lossy: b44, b44a on HALF; dwaa, dwab (a DCT of R, G, B and Y, both types).
enum class ExrCompression { None, Rle, Zips, Zip, Piz, Pxr24, B44, B44a, Dwaa, Dwab };

// "none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab".
const char* toString(ExrCompression compression);
// Every compression, in the order above.
const std::vector<ExrCompression>& exrCompressions();
// The compression named `name` (any case); throws InvalidArgument naming it and the choices.
ExrCompression exrCompressionNamed(std::string_view name);
// Whether a file written with `compression` reads back the values written: bit-exact floats, or
// for HALF channels exactly the half-rounded values.
bool isLossless(ExrCompression compression, bool half);

struct ExrWriteOptions {
    // Lossless and the fastest: a denoised image's float values barely compress, and deflating
    // them takes longer than denoising them (docs/performance-cpu.md, 2026-12-02).
    ExrCompression compression = ExrCompression::None;
    bool half = false;  // HALF channels (values rounded to the nearest half) instead of FLOAT
};

// Linear EXR: R,G,B for 3 channels, Y for 1; FLOAT (or HALF) channels, compressed as asked.
void writeExr(const std::filesystem::path& file, const Image& image,
              const ExrWriteOptions& options);
// The same with the default options.
void writeExr(const std::filesystem::path& file, const Image& image);
// Threads OpenEXR uses to decompress and compress one file's blocks (0, its default: the
// calling thread alone). Process-wide, as OpenEXR's own setting is; the CLI sets the core count.
void setExrThreads(int count);
// 8-bit RGB PNG of an already display-encoded image (values in [0,1], 3 channels).
void writePng(const std::filesystem::path& file, const Image& image);

// ---- display ----

// Narkowicz's ACES fit x(2.51x+0.03)/(x(2.43x+0.59)+0.14), clamped to [0,1].
float acesFilm(float x);
// Linear [0,1] to sRGB-encoded [0,1].
float linearToSrgb(float x);
// exposure * linear -> ACES -> sRGB, per channel, NaN-safe (non-finite becomes 0).
Image toneMap(const Image& linear, float exposure = 1.0f);

// Encodes frames to an H.264 MP4 through the `ffmpeg` program. Frames are tone-mapped images
// ([0,1], 3 channels) of one size. Throws MissingTool if ffmpeg is not on PATH.
class VideoWriter {
  public:
    VideoWriter(std::filesystem::path file, int width, int height, int framesPerSecond = 24);
    ~VideoWriter();  // abandons an unfinished video (the temporary file is removed)
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    void addFrame(const Image& displayImage);
    void finish();  // waits for ffmpeg and renames the temporary file into place

    static bool ffmpegAvailable();

  private:
    std::filesystem::path file_;
    std::filesystem::path tempFile_;
    int width_, height_;
    void* pipe_ = nullptr;                              // FILE* writing to ffmpeg's standard input
    int childPid_ = 0;                                  // ffmpeg
    int tempRegistration_ = -1, logRegistration_ = -1;  // for abandonTemporaryFiles
    std::vector<unsigned char> rowBuffer_;
};

// For a program's SIGINT/SIGTERM handler (the library installs none): stops the ffmpeg child of
// an unfinished video and removes every temporary file a writer has open, so an interrupted run
// leaves neither behind. Async-signal-safe: kill, waitpid and unlink of paths stored in advance.
void abandonTemporaryFiles() noexcept;

// Throws IoFailure naming `folder` unless prepareOutputFolder(folder) would succeed: it is a
// writable folder, or can be created under the nearest existing folder. Creates nothing.
void checkOutputFolder(const std::filesystem::path& folder);

// Throws IoFailure naming `file` unless it could be written: its folder exists (a folder, not a
// file) and `file` is not itself a folder. Creates nothing.
void checkOutputFile(const std::filesystem::path& file);

// Creates `folder` (and its parents) if needed and checks that a file can be written in it;
// throws IoFailure naming the folder otherwise. Call before a long job, not after it.
void prepareOutputFolder(const std::filesystem::path& folder);

// Writes `bytes` to `file` through a temporary name in the same folder and a rename.
void writeFileAtomically(const std::filesystem::path& file, const std::string& bytes);

}  // namespace rtd
