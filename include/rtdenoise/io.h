// Reading course-layout sequences and writing results. Every function throws rtd::Error with the
// file's path and the problem; writers write to a temporary name and rename, so no file is ever
// left half-written.
#pragma once

#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rtdenoise/image.h"

namespace rtd {

// ---- reading ----

// One entry per output channel, each listing acceptable names in the file, first match wins
// (e.g. {{"R"}, {"G"}, {"B"}} or {{"Y", "Z", "R"}}).
using ChannelChoices = std::vector<std::vector<std::string>>;

// Reads the named channels of an EXR (HALF or FLOAT, any compression OpenEXR reads) into an
// interleaved float image.
Image readExr(const std::filesystem::path& file, const ChannelChoices& channelChoices);

// Several images from one EXR in one pass over its pixels (a multilayer file's passes):
// images[k] holds the channels of images[k]'s choices.
std::vector<Image> readExrImages(const std::filesystem::path& file,
                                 const std::vector<ChannelChoices>& images);

// What readExr would return, from the header alone (no pixels read): the image's size, after
// the checks readExr makes before reading (the file, the channels, a plausible size).
struct ExrSize {
    int width = 0;
    int height = 0;
};
ExrSize readExrSize(const std::filesystem::path& file, const ChannelChoices& channelChoices);

// An EXR's size and channel names (in the order the header lists them) from its header, after
// the checks readExr makes on it.
struct ExrContents {
    ExrSize size;
    std::vector<std::string> channels;
};
ExrContents readExrContents(const std::filesystem::path& file);

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

// Removes the regular files "<stem>_<i><extension>" of `folder` with firstRemoved <= i <
// endRemoved (0 and the default: all of them): outputs of an earlier run that this one does not
// rewrite. Nothing else is touched (a chunk's run leaves the other chunks' files alone).
void removeNumberedFiles(const std::filesystem::path& folder, std::string_view stem,
                         std::string_view extension, int firstRemoved,
                         int endRemoved = std::numeric_limits<int>::max());

// ---- frame sources ----

// A sequence of frames on disk in one of the layouts rtdenoise reads: the course folder
// (Sequence) or the multilayer EXRs Blender writes for an animation (BlenderSequence).
// openFrameSource picks the one a path names. Frames are indexed 0..frameCount()-1 whatever
// the files' own numbers (firstFrameNumber() + index: beauty_<i>.exr's i, or Blender's 0001.exr's
// 1); readFrame is const and may run on another thread than the caller's.
class FrameSource {
  public:
    virtual ~FrameSource() = default;

    virtual int frameCount() const = 0;
    // Reads and validates frame i (0..frameCount()-1), as image.h documents a Frame.
    virtual Frame readFrame(int index) const = 0;
    // The input's own number of frame index 0 (the folder layout: 0; Blender's files: the first
    // file's number). Numbers are contiguous: frame i is number firstFrameNumber() + i.
    virtual int firstFrameNumber() const { return 0; }
    // Checks frames firstIndex..firstIndex+count-1 as far as can be done without reading pixels
    // (files present, headers with the channels readFrame reads, one size per frame, any side
    // files), so that a long run does not fail at frame i. Returns each frame's size.
    virtual std::vector<ExrSize> checkFrames(int count, int firstIndex = 0) const = 0;
    // One line for progress messages: the path and the layout ("... (course layout)").
    virtual std::string describe() const = 0;
    // The file that stands for frame i in messages: its beauty, or its multilayer EXR.
    virtual std::filesystem::path frameFile(int index) const = 0;
    // What this source lacks and how its frames are degraded for it (an optional pass it has no
    // file for), one sentence each, for the caller to show once per run.
    virtual std::vector<std::string> warnings() const { return {}; }
    // Why its frames cannot be projected into the previous frame (no matrices, no motion
    // vectors), naming the file and what to enable; "" when they can. History methods need it.
    virtual std::string backProjectionProblem() const { return {}; }
};

// A folder in the course layout: beauty_i.exr, normal_i.exr, position_i.exr, depth_i.exr,
// ID_i.exr, matrix_i.mat, optional albedo_i.exr and confidence_i.exr (history confidence: Y, or
// the R of an RGB file), and the optional split signal: specular_i.exr (RGB), roughness_i.exr and
// hit_distance_i.exr (Y, or the R of an RGB file; Frame::roughness and Frame::hitDistance), for
// i = 0..frameCount-1.
class Sequence : public FrameSource {
  public:
    // Discovers the frame count from beauty_<i>.exr; throws if none, or on a gap in the numbering.
    explicit Sequence(std::filesystem::path folder);

    int frameCount() const override { return frameCount_; }
    const std::filesystem::path& folder() const { return folder_; }

    // Reads and validates frame i: all buffers the same size, IDs in -1..K-1.
    Frame readFrame(int index) const override;

    // Checks frames firstIndex..firstIndex+count-1 as far as can be done without reading pixels,
    // so that a long run does not fail at frame i: every file present, EXR headers with the
    // channels readFrame reads, the buffers of a frame of one size, every matrix_i.mat read and
    // validated. Returns each frame's size. Only the IDs (pixel values) are left to readFrame.
    std::vector<ExrSize> checkFrames(int count, int firstIndex = 0) const override;

    std::string describe() const override;
    std::filesystem::path frameFile(int index) const override;

  private:
    std::filesystem::path folder_;
    int frameCount_ = 0;
};

// A contiguous run of numbered files in one folder, as renderers name an animation's frames:
// prefix + number + suffix, the number zero-padded to `digits` ("0001.exr", "frame_0001.exr").
struct NumberedFiles {
    std::filesystem::path folder;
    std::string prefix;
    std::string suffix;
    int digits = 1;  // the width numbers are zero-padded to (1: unpadded)
    int first = 0;   // the number of the first file
    int count = 0;
    // The file of index i = 0..count-1: number first + i.
    std::filesystem::path file(int index) const;
    // "DIR/frame_####.exr", the Blender-style pattern of these files.
    std::string pattern() const;
};

// Whether a path's file name holds a frame-number placeholder: %d, %0Nd or a run of '#'.
bool isFramePattern(const std::filesystem::path& path);

// The numbered files `input` names: a folder (its numbered `extension` files, which must share
// one prefix: "0001.exr" or "name_0001.exr"), or a pattern whose file name holds one %d, %0Nd or
// run of N '#' (Blender's: the number zero-padded to N digits). Numbering may start anywhere but
// must be contiguous. Throws MissingFile (no such folder, no matching file), InvalidInput naming
// the first missing file on a gap, or for a folder of several names, or of files of one name
// that fit no single padding (0001.exr and 5.exr: it names each numbering's files), or a
// matching entry that is not a regular file.
NumberedFiles findNumberedFiles(const std::filesystem::path& input,
                                std::string_view extension = ".exr");

// Cycles' Depth where a ray hits nothing (the background).
constexpr float kCyclesMissDepth = 1e10f;

// The multilayer EXRs Blender (Cycles) writes for an animation, one file per frame, channels
// "<view layer>.<pass>.<component>": Noisy Image (preferred: Combined may be denoised) or
// Combined, Depth, Normal, Position required; IndexOB, Denoising Albedo, Vector optional
// (docs/inputs.md). Frames come with motion vectors and without matrices:
// - background where Depth is Cycles' miss value (ID -1, normal, position and depth 0);
// - IDs from IndexOB (the objects' pass_index), objectCount = the frame's largest + 1; without
//   IndexOB every object pixel is ID 0;
// - motion from Vector: Blender's (X, Y) points to the previous frame, in pixels with y up, so
//   motion = (X, -Y) in the Frame's y-down convention;
// - depth: Cycles' Depth is the distance from the camera plane (DepthKind::ViewZ);
// - albedo from Denoising Albedo; without it, none (no demodulation).
class BlenderSequence : public FrameSource {
  public:
    // `input` as findNumberedFiles takes it. `viewLayer` names the view layer to read (empty:
    // the first one, in the file's channel order, with every required pass; when several layers
    // are there and none has them all, InvalidInput says what each lacks). Reads the first
    // file's header: a required pass missing there throws InvalidInput naming the pass, the file
    // and how to enable it in Blender; a pass present in part (Normal without Z) names the
    // channels missing.
    explicit BlenderSequence(const std::filesystem::path& input, std::string viewLayer = {});

    int frameCount() const override { return files_.count; }
    int firstFrameNumber() const override { return files_.first; }
    Frame readFrame(int index) const override;
    // Every file's header holds the passes the first one has and no optional pass it lacks (the
    // sequence reads the same passes from each), the view layer, and a plausible size.
    std::vector<ExrSize> checkFrames(int count, int firstIndex = 0) const override;
    std::string describe() const override;
    std::filesystem::path frameFile(int index) const override { return files_.file(index); }
    std::vector<std::string> warnings() const override { return warnings_; }
    std::string backProjectionProblem() const override;

    const NumberedFiles& files() const { return files_; }
    const std::string& viewLayer() const { return layer_; }
    const std::string& colourPass() const { return colourPass_; }  // "Noisy Image" or "Combined"
    bool hasObjectIndex() const { return hasObjectIndex_; }
    bool hasAlbedo() const { return hasAlbedo_; }
    bool hasMotion() const { return hasMotion_; }

  private:
    std::vector<ChannelChoices> channelsRead() const;
    void requirePasses(const std::filesystem::path& file, const ExrContents& contents) const;

    NumberedFiles files_;
    std::string layer_;
    std::string colourPass_;
    bool hasObjectIndex_ = false;
    bool hasAlbedo_ = false;
    bool hasMotion_ = false;
    std::vector<std::string> warnings_;
};

struct FrameSourceOptions {
    std::string viewLayer;  // Blender input: the view layer to read (empty: the first)
};

// The frame source `input` names: a folder with beauty_<i>.exr is the course layout; a folder of
// numbered EXRs without them, or a file pattern (%04d, ####), Blender's multilayer EXRs. Throws
// MissingFile naming the path when it is neither.
std::unique_ptr<FrameSource> openFrameSource(const std::filesystem::path& input,
                                             const FrameSourceOptions& options = {});

// ---- chunks of a shot ----

// The warm-up a chunk runs before its first frame when none is given: the frames whose history
// makes a chunk's first frame match a run over the whole shot (docs/farm.md, measured).
constexpr int kDefaultChunkWarmup = 48;

// A chunk of a sequence as frame indices (0..frameCount()-1): frames warmupIndex..firstIndex-1
// are denoised for their history only, firstIndex..endIndex-1 are the chunk's results.
struct FrameChunk {
    int warmupIndex = 0;
    int firstIndex = 0;
    int endIndex = 0;
};

// The chunk of input frame numbers firstNumber..endNumber-1 (the files' own numbers:
// beauty_<i>.exr's i, Blender's 0001.exr's 1) after `warmup` frames, fewer where the sequence
// starts sooner. Throws InvalidArgument naming the source and the numbers it holds when the
// range is empty or reaches outside them, or the warm-up is negative.
FrameChunk chunkOf(const FrameSource& source, int firstNumber, int endNumber, int warmup);

// The R, G, B channels of an EXR's colour: R, G, B of a plain EXR, else the Combined pass of a
// Blender multilayer EXR's first view layer (or of `viewLayer`). Throws InvalidInput naming the
// file when it has neither.
ChannelChoices colourChannelsOf(const std::filesystem::path& file,
                                const std::string& viewLayer = {});

// ---- writing ----

// Writes frame `index` of `frame` in the course layout into `folder` (beauty, normal, position,
// depth, ID, matrix, and albedo, confidence, specular, roughness and hit_distance when the frame
// has them): what Sequence reads back, the EXRs with writeExr's default options. Creates the
// folder if needed.
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

// One image of a multi-channel EXR: channel c is written as `names[c]` (names.size() ==
// image->channels), FLOAT or HALF.
struct ExrChannelGroup {
    const Image* image = nullptr;
    std::vector<std::string> names;
    bool half = false;
};
// Writes the groups' channels (images of one size) into one scanline EXR, ZIP-compressed.
void writeExrChannels(const std::filesystem::path& file,
                      const std::vector<ExrChannelGroup>& groups);

// Writes `frame` as the multilayer EXR Cycles writes (BlenderSequence reads it back): passes
// Combined (RGBA, A = 1), Depth (view depth, kCyclesMissDepth on background), Normal, Position
// (0 on background), IndexOB (the ID, 0 on background), Denoising Albedo (when the frame has an
// albedo) and Vector (when it has motion: X, Y = frame.motion with y up, pointing to the
// previous frame; Z, W = minus `motionToNext` with y up, from the next frame), all FLOAT, in view
// layer `viewLayer`. Needs DepthKind::ViewZ; motionToNext (2 channels, pixels, y down: next
// minus current) defaults to none (Z = W = 0).
void writeBlenderExr(const std::filesystem::path& file, const Frame& frame,
                     const Image* motionToNext = nullptr,
                     const std::string& viewLayer = "ViewLayer");
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
// For the process's end: a file being created is waited for, and later writes fail (IoFailure).
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
