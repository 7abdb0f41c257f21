// A method as a declaration: typed resources (kind, planes, lifetime) and named passes that read
// and write them, each running one logical kernel (devices/steps.h). From the declaration, in
// one place: the images' border (the widest pass's reach), their allocation, the pass list users
// see, per-pass timing and the debug views. A pass can touch only the resources it declares.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "devices/device.h"
#include "rtdenoise/denoiser.h"

namespace rtd {

enum class Element { Float, Int32, Byte };

enum class Lifetime {
    Frame,    // written and read within a frame
    History,  // kept across frames: this frame's copy and the last one's (swapped per frame)
    External  // not allocated: the frame's buffers, its matrices, the caller's output
};

// How a debug view (Denoiser::debugImage) shows a resource's plane.
enum class DebugShow {
    ReprojectionCodes,  // ReprojectionCode per pixel, as colours
    StandardDeviation,  // sqrt of a variance, clipped at 1
    Scaled,             // value divided by `debugDivisor`
};

struct ResourceDecl {
    std::string name;
    Element element = Element::Float;
    int planes = 1;
    Lifetime lifetime = Lifetime::Frame;
    std::uint8_t fillByte = 0;  // every byte's value when allocated; the border keeps it
    bool padded = true;         // false: one value per pixel of the frame, no border
    int tile = 0;               // > 0 (with padded false): one value per tile x tile pixels
    // A debug view of this resource, the frame just processed (none: DebugView count).
    bool hasDebugView = false;
    DebugView debugView = DebugView::Reprojection;
    int debugPlane = 0;
    DebugShow debugShow = DebugShow::Scaled;
    float debugDivisor = 1.0f;
};

// A declared resource; previous(): a history's copy from the last frame.
struct ResourceId {
    int index = -1;
    bool last = false;
};
inline ResourceId previous(ResourceId r) {
    r.last = true;
    return r;
}

// The frame as the passes see it (set by the Denoiser before each frame).
struct FrameBinding {
    const float* beauty = nullptr;  // interleaved RGB, in the device's memory space
    const float* normal = nullptr;
    const float* position = nullptr;
    const float* depth = nullptr;
    const std::int32_t* objectId = nullptr;
    const float* albedo = nullptr;  // null: no demodulation
    InputSpan motion;               // the caller's motion vectors (data null: the matrices)
    // The caller's history confidence, 1 channel in [0, 1] (data null: none): 0 where the
    // lighting changed and the history should be dropped (NRD's IN_DIFF_CONFIDENCE).
    InputSpan confidence;
    InputSpan specular;     // the caller's specular part of beauty, RGB (data null: none)
    InputSpan roughness;    // with specular: 1 channel in [0, 1] (sqrt of GGX alpha)
    InputSpan hitDistance;  // with specular, optional: specular hit distance (0: unknown)
    Float3 cameraPosition;  // world space (from worldToCamera), where the views start
    int objectCount = 0;
    const ObjectReprojection* objects = nullptr;  // the matrices, one per object
    int hasHistory = 0;
    float* output = nullptr;  // interleaved RGB, as the device sees it
};

class Pipeline;

// One pass's view of the resources it declared, this frame.
class PassContext {
  public:
    const Layout& layout() const;
    Device& device() const { return device_; }
    Planes3 planes(ResourceId r) const { return {floats(r), planeSize()}; }
    PlaneSet planeSet(ResourceId r) const { return {floats(r), planeSize()}; }
    float* floats(ResourceId r) const { return static_cast<float*>(memory(r, Element::Float)); }
    std::int32_t* ints(ResourceId r) const {
        return static_cast<std::int32_t*>(memory(r, Element::Int32));
    }
    std::uint8_t* bytes(ResourceId r) const {
        return static_cast<std::uint8_t*>(memory(r, Element::Byte));
    }
    // The frame's buffers (declared as a read of Pipeline::frame()), its matrices
    // (Pipeline::matrices()) and the output (a write of Pipeline::output()).
    const FrameBinding& frame() const;
    const ObjectReprojection* objects() const;
    float* output() const;

  private:
    friend class Pipeline;
    PassContext(const Pipeline& pipeline, Device& device, const FrameBinding& frame, int pass)
        : pipeline_(pipeline), device_(device), frame_(frame), pass_(pass) {}
    int planeSize() const;
    void* memory(ResourceId r, Element element) const;
    void require(ResourceId r, bool write) const;
    const Pipeline& pipeline_;
    Device& device_;
    const FrameBinding& frame_;
    int pass_;
};

class Pipeline {
  public:
    Pipeline();

    ResourceId declare(ResourceDecl decl);
    // reach: how far from a pixel the pass reads, in pixels (the border covers the widest).
    void addPass(std::string name, StepKind step, std::vector<ResourceId> reads,
                 std::vector<ResourceId> writes, int reach,
                 std::function<void(const PassContext&)> run);

    // The external resources every method has.
    ResourceId frame() const { return {0}; }
    ResourceId matrices() const { return {1}; }
    ResourceId output() const { return {2}; }

    const std::vector<PassInfo>& passes() const { return passInfos_; }
    int reach() const { return reach_; }
    bool keepsHistory() const;

    // Lays out and allocates every resource for w x h frames (zero history), and lets the
    // device prepare its forms of the passes' steps.
    void allocate(Device& device, int width, int height);
    const Layout& layout() const { return layout_; }
    std::uint8_t* frameBytes(ResourceId r) const { return static_cast<std::uint8_t*>(at(r)); }

    // Runs every pass, timing each between device timestamps (slot p to p + 1).
    void run(Device& device, const FrameBinding& frame);
    // After a frame: this frame's history copies become the last frame's.
    void endFrame() { current_ = 1 - current_; }
    // Takes `from`'s images (and so its history) where both declare the same passes over the same
    // resources, as after a change of settings the passes merely read (a sigma); false, and
    // nothing taken, where they differ.
    bool adoptImages(Pipeline& from);

    // The debug view of the frame just processed (black where no resource has it).
    Image debugImage(Device& device, DebugView view) const;
    // A debug view made of every plane of `sources`, in order, as they are (int32 planes: 1
    // where >= 0, an object's key, else 0): a method's intermediate images for its training.
    void addDebugImage(DebugView view, std::vector<ResourceId> sources);

  private:
    friend class PassContext;
    struct Pass {
        std::function<void(const PassContext&)> run;
        std::vector<std::uint8_t> access;  // per resource copy (2 per resource): 1 read, 2 write
    };
    std::vector<std::pair<DebugView, std::vector<ResourceId>>> debugImages_;
    Image gatheredDebugImage(Device& device, const std::vector<ResourceId>& sources) const;
    void* at(ResourceId r) const;
    std::size_t count(const ResourceDecl& d) const;

    std::vector<ResourceDecl> resources_;
    std::vector<Pass> passes_;
    std::vector<PassInfo> passInfos_;
    std::vector<StepKind> steps_;
    int reach_ = 0;
    Layout layout_;
    int current_ = 0;
    // Two copies per resource (the second for histories); storage as bytes of any element.
    std::vector<DeviceBuffer<std::uint8_t>> memory_;
};

}  // namespace rtd
