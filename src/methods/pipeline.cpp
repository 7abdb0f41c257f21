#include "methods/pipeline.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rtdenoise/error.h"

namespace rtd {
namespace {

std::size_t elementBytes(Element e) {
    return e == Element::Byte ? 1 : 4;
}

constexpr std::uint8_t kRead = 1, kWrite = 2;

}  // namespace

const Layout& PassContext::layout() const {
    return pipeline_.layout_;
}
int PassContext::planeSize() const {
    return pipeline_.layout_.planeSize;
}

void PassContext::require(ResourceId r, bool write) const {
    const auto& access = pipeline_.passes_[std::size_t(pass_)].access;
    std::size_t k = 2 * std::size_t(r.index) + (r.last ? 1 : 0);
    if (r.index < 0 || k >= access.size() || !(access[k] & (write ? kWrite : kRead)))
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("pipeline: pass '{}' {} '{}{}' without declaring it",
                                pipeline_.passInfos_[std::size_t(pass_)].name,
                                write ? "writes" : "reads", r.last ? "previous " : "",
                                r.index >= 0 && std::size_t(r.index) < pipeline_.resources_.size()
                                    ? pipeline_.resources_[std::size_t(r.index)].name
                                    : "?"));
}

void* PassContext::memory(ResourceId r, Element element) const {
    const auto& access = pipeline_.passes_[std::size_t(pass_)].access;
    std::size_t k = 2 * std::size_t(r.index) + (r.last ? 1 : 0);
    if (r.index < 0 || k >= access.size() || access[k] == 0)
        require(r, false);  // throws, naming the pass and the resource
    const ResourceDecl& d = pipeline_.resources_[std::size_t(r.index)];
    if (d.element != element || d.lifetime == Lifetime::External)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("pipeline: pass '{}' reads '{}' as another element type",
                                pipeline_.passInfos_[std::size_t(pass_)].name, d.name));
    return pipeline_.at(r);
}

const FrameBinding& PassContext::frame() const {
    require(pipeline_.frame(), false);
    return frame_;
}
const ObjectReprojection* PassContext::objects() const {
    require(pipeline_.matrices(), false);
    return frame_.objects;
}
float* PassContext::output() const {
    require(pipeline_.output(), true);
    return frame_.output;
}

Pipeline::Pipeline() {
    declare({.name = "frame", .lifetime = Lifetime::External});
    declare({.name = "matrices", .lifetime = Lifetime::External});
    declare({.name = "output", .lifetime = Lifetime::External});
}

ResourceId Pipeline::declare(ResourceDecl decl) {
    resources_.push_back(std::move(decl));
    return {int(resources_.size()) - 1};
}

void Pipeline::addPass(std::string name, StepKind step, std::vector<ResourceId> reads,
                       std::vector<ResourceId> writes, int reach,
                       std::function<void(const PassContext&)> run) {
    if (int(passes_.size()) + 1 >= Device::kTimestampSlots)
        throw Error(ErrorCode::InvalidArgument, "settings: too many passes to time");
    Pass pass{std::move(run), std::vector<std::uint8_t>(2 * resources_.size(), 0)};
    PassInfo info{std::move(name), {}, {}};
    auto note = [&](ResourceId r, std::uint8_t mode, std::vector<std::string>& names) {
        const ResourceDecl& d = resources_.at(std::size_t(r.index));
        if (r.last && d.lifetime != Lifetime::History)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("pipeline: '{}' keeps no previous frame", d.name));
        pass.access[2 * std::size_t(r.index) + (r.last ? 1 : 0)] |= mode;
        names.push_back((r.last ? "previous " : "") + d.name);
    };
    for (ResourceId r : reads) note(r, kRead, info.inputs);
    for (ResourceId r : writes) note(r, kWrite, info.outputs);
    passes_.push_back(std::move(pass));
    passInfos_.push_back(std::move(info));
    steps_.push_back(step);
    reach_ = std::max(reach_, reach);
}

bool Pipeline::keepsHistory() const {
    return std::any_of(resources_.begin(), resources_.end(),
                       [](const ResourceDecl& d) { return d.lifetime == Lifetime::History; });
}

std::size_t Pipeline::count(const ResourceDecl& d) const {
    const auto tiles = [&](int size) { return std::size_t((size + d.tile - 1) / d.tile); };
    std::size_t perPlane = d.padded     ? std::size_t(layout_.planeSize)
                           : d.tile > 0 ? tiles(layout_.width) * tiles(layout_.height)
                                        : std::size_t(layout_.width) * std::size_t(layout_.height);
    return std::size_t(d.planes) * perPlane * elementBytes(d.element);
}

void Pipeline::allocate(Device& device, int width, int height) {
    // Rows padded to whole cache lines; the border (see kernels/views.h) rounded up likewise so
    // that pixel (0, 0) is aligned.
    constexpr int kAlign = 16;
    int border = (reach_ + kAlign - 1) / kAlign * kAlign;
    Layout L;
    L.width = width;
    L.height = height;
    L.padding = border;
    // In 64 bits: a width near INT_MAX must be refused here, not overflow into a small pitch.
    const long long pitch =
        (static_cast<long long>(width) + 2 * border + kAlign - 1) / kAlign * kAlign;
    const long long planeSize = pitch * (static_cast<long long>(height) + 2 * border);
    // Pixel indices are 32-bit (the widest image has 7 planes).
    if (7 * planeSize > 0x7fffffffLL)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("frame: {}x{} is too large for one device image", width, height));
    L.pitch = int(pitch);
    L.origin = border * L.pitch + border;
    L.planeSize = int(planeSize);
    memory_.clear();  // the old images first: no moment with both held
    layout_ = L;
    memory_.resize(2 * resources_.size());
    for (std::size_t k = 0; k < resources_.size(); ++k) {
        const ResourceDecl& d = resources_[k];
        if (d.lifetime == Lifetime::External) continue;
        for (int copy = 0; copy < (d.lifetime == Lifetime::History ? 2 : 1); ++copy) {
            DeviceBuffer<std::uint8_t>& b = memory_[2 * k + std::size_t(copy)];
            b = DeviceBuffer<std::uint8_t>(device, count(d));
            device.fill(b.data(), d.fillByte, b.bytes());
        }
    }
    current_ = 0;
    device.prepare(layout_, steps_);
}

bool Pipeline::adoptImages(Pipeline& from) {
    auto sameImage = [](const ResourceDecl& a, const ResourceDecl& b) {
        return a.name == b.name && a.element == b.element && a.planes == b.planes &&
               a.lifetime == b.lifetime && a.fillByte == b.fillByte && a.padded == b.padded &&
               a.tile == b.tile;
    };
    auto samePass = [](const PassInfo& a, const PassInfo& b) {
        return a.name == b.name && a.inputs == b.inputs && a.outputs == b.outputs;
    };
    const bool same = reach_ == from.reach_ && steps_ == from.steps_ &&
                      std::equal(resources_.begin(), resources_.end(), from.resources_.begin(),
                                 from.resources_.end(), sameImage) &&
                      std::equal(passInfos_.begin(), passInfos_.end(), from.passInfos_.begin(),
                                 from.passInfos_.end(), samePass);
    if (!same) return false;
    // The device prepared its forms of these same steps for this layout already.
    memory_ = std::move(from.memory_);
    layout_ = from.layout_;
    current_ = from.current_;
    from.memory_.clear();
    from.layout_ = Layout{};
    return true;
}

void* Pipeline::at(ResourceId r) const {
    const ResourceDecl& d = resources_[std::size_t(r.index)];
    int copy = d.lifetime == Lifetime::History ? (r.last ? 1 - current_ : current_) : 0;
    return memory_[2 * std::size_t(r.index) + std::size_t(copy)].data();
}

void Pipeline::run(Device& device, const FrameBinding& frame) {
    device.recordTimestamp(0);
    for (std::size_t p = 0; p < passes_.size(); ++p) {
        passes_[p].run(PassContext(*this, device, frame, int(p)));
        device.recordTimestamp(int(p) + 1);
    }
}

void Pipeline::addDebugImage(DebugView view, std::vector<ResourceId> sources) {
    debugImages_.emplace_back(view, std::move(sources));
}

Image Pipeline::gatheredDebugImage(Device& device, const std::vector<ResourceId>& sources) const {
    int channels = 0;
    for (ResourceId r : sources) channels += resources_[std::size_t(r.index)].planes;
    Image image(layout_.width, layout_.height, channels);
    int channel = 0;
    for (ResourceId source : sources) {
        const ResourceDecl& d = resources_[std::size_t(source.index)];
        // The frame just processed: endFrame() has made its history copies the "previous" ones.
        const ResourceId r{source.index, d.lifetime == Lifetime::History};
        const std::size_t plane = std::size_t(layout_.planeSize) * elementBytes(d.element);
        std::vector<std::uint8_t> padded(plane * std::size_t(d.planes));
        device.copyToHost(padded.data(), at(r), padded.size());
        for (int p = 0; p < d.planes; ++p, ++channel)
            for (int y = 0; y < layout_.height; ++y)
                for (int x = 0; x < layout_.width; ++x) {
                    const std::size_t offset =
                        std::size_t(p) * plane +
                        elementBytes(d.element) * std::size_t(layout_.index(x, y));
                    float v;
                    if (d.element == Element::Int32) {
                        std::int32_t key;
                        std::memcpy(&key, &padded[offset], sizeof key);
                        v = key >= 0 ? 1.0f : 0.0f;
                    } else if (d.element == Element::Byte) {
                        v = float(padded[offset]);
                    } else {
                        std::memcpy(&v, &padded[offset], sizeof v);
                    }
                    image.at(x, y, channel) = v;
                }
    }
    return image;
}

Image Pipeline::debugImage(Device& device, DebugView view) const {
    for (const auto& [gathered, sources] : debugImages_)
        if (gathered == view && layout_.width > 0) return gatheredDebugImage(device, sources);
    Image image(layout_.width, layout_.height, 3);
    auto found = std::find_if(resources_.begin(), resources_.end(), [&](const ResourceDecl& d) {
        return d.hasDebugView && d.debugView == view;
    });
    if (found == resources_.end() || layout_.width == 0) return image;
    const ResourceDecl& d = *found;
    // The frame just processed: endFrame() has made its history copies the "previous" ones.
    ResourceId r{int(found - resources_.begin()), d.lifetime == Lifetime::History};
    std::size_t plane = std::size_t(layout_.planeSize) * elementBytes(d.element);
    std::vector<std::uint8_t> padded(plane);
    device.copyToHost(padded.data(), static_cast<const std::uint8_t*>(at(r)) + d.debugPlane * plane,
                      plane);
    static const float kCodeColours[5][3] = {
        {0.0f, 1.0f, 0.0f},  // valid: green
        {1.0f, 0.0f, 0.0f},  // outside the screen: red
        {1.0f, 1.0f, 0.0f},  // other object (or depth/normal disagree): yellow
        {0.0f, 0.0f, 1.0f},  // background: blue
        {0.0f, 0.0f, 0.0f},  // no history: black
    };
    for (int y = 0; y < layout_.height; ++y)
        for (int x = 0; x < layout_.width; ++x) {
            std::size_t i = std::size_t(layout_.index(x, y));
            float* out = &image.pixels[3 * (std::size_t(y) * layout_.width + x)];
            if (d.debugShow == DebugShow::ReprojectionCodes) {
                for (int c = 0; c < 3; ++c) out[c] = kCodeColours[padded[i] % 5][c];
                continue;
            }
            float v;
            std::memcpy(&v, &padded[4 * i], sizeof v);
            v = d.debugShow == DebugShow::StandardDeviation
                    ? std::min(1.0f, std::sqrt(std::max(v, 0.0f)))
                    : v / d.debugDivisor;
            for (int c = 0; c < 3; ++c) out[c] = v;
        }
    return image;
}

}  // namespace rtd
