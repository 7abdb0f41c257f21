// Kernels run directly on the CPU device over padded buffers built like the Denoiser's, for
// kernel-level known-answer tests.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "devices/cpu/cpu_scratch.h"
#include "devices/cpu/parallel_for.h"
#include "devices/device.h"

namespace rtd {

// A small deterministic generator of floats in [0, 1) (a linear congruential generator), the
// same sequence on every platform.
struct UnitRandom {
    std::uint32_t state;
    float operator()() {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1 << 24);
    }
};

// How far another form of a kernel (pixel pairs, pairs shared between rows, another layout) may
// land from the reference form's `value`: it sums the same terms in another order.
inline float roundingTolerance(float value) {
    return 1e-5f * std::fabs(value) + 1e-7f;
}
// Every channel of `got` within roundingTolerance of `want`'s.
inline ::testing::AssertionResult nearUpToRounding(Float3 got, Float3 want) {
    const float g[3] = {got.x, got.y, got.z}, w[3] = {want.x, want.y, want.z};
    for (int c = 0; c < 3; ++c)
        if (!(std::fabs(g[c] - w[c]) <= roundingTolerance(w[c])))
            return ::testing::AssertionFailure()
                   << "channel " << c << ": " << g[c] << " against " << w[c];
    return ::testing::AssertionSuccess();
}

// Runs a kernel's GPU form in pixel pairs (filterPair<Stride>) over a w x h image on the CPU,
// with the CUDA launcher's mapping (PairedRows): thread row r takes row top = 2 Stride
// floor(r / Stride) + r mod Stride and the row Stride below it; a top whose partner lies outside
// the image is filtered alone. stride: 1, 2 or 4.
template <class Kernel>
void runInPixelPairs(const Kernel& kernel, int stride, int w, int h) {
    auto run = [&]<int Stride>() {
        const int threadRows = (h + 2 * Stride - 1) / (2 * Stride) * Stride;
        for (int r = 0; r < threadRows; ++r) {
            const int top = r / Stride * (2 * Stride) + r % Stride;
            for (int x = 0; x < w; ++x) {
                if (top + Stride < h)
                    kernel.template filterPair<Stride>(x, top);
                else if (top < h)
                    kernel.template filter<Stride>(x, top);
            }
        }
    };
    stride == 1   ? run.template operator()<1>()
    : stride == 2 ? run.template operator()<2>()
                  : run.template operator()<4>();
}

// Runs a tile kernel over a w x h image on the CPU as the CUDA launcher does (runTileKernel):
// per tile and phase, the items of each of `threads` threads (runPhaseItems), the threads taken
// last to first. Shared starts each tile as NaN: an item that read an entry no earlier phase
// wrote (or another item of its own phase, not yet run) would spread a NaN or a wrong value.
template <class Kernel>
void runTilesAsBlocks(const Kernel& kernel, int w, int h, int threads = 256) {
    auto shared = std::make_unique<typename Kernel::Shared>();
    for (int tileY = 0; tileY < h; tileY += Kernel::kTileHeight)
        for (int tileX = 0; tileX < w; tileX += Kernel::kTileWidth) {
            std::memset(static_cast<void*>(shared.get()), 0xff, sizeof(typename Kernel::Shared));
            [&]<int... Phase>(std::integer_sequence<int, Phase...>) {
                auto phase = [&]<int P>() {
                    for (int t = threads - 1; t >= 0; --t)
                        runPhaseItems<P>(kernel, *shared, tileX, tileY, t, threads);
                };
                (phase.template operator()<Phase>(), ...);
            }
            (std::make_integer_sequence<int, Kernel::kPhases>{});
        }
}

// The CPU device, and any single kernel run on it as the CPU device runs its forms
// (parallelFor2D, with the device's scratch): the GPU's forms too, which the device itself
// never picks.
class TestDevice {
  public:
    operator Device&() { return *device_; }
    Device* operator->() { return device_.get(); }
    void fill(void* p, int value, std::size_t bytes) { device_->fill(p, value, bytes); }
    template <class Kernel>
    void launch(const Kernel& kernel, int width, int height) {
        parallelFor2D(width, height, kernel, &scratch_);
    }

  private:
    std::unique_ptr<Device> device_ = createCpuDevice();
    CpuScratch scratch_{*device_};
};

// Padded planar buffers for a w x h image, as the Denoiser lays them out.
struct Harness {
    // A flat wall facing the camera (normal -z, z = 5), one object, everything else 0.
    std::unique_ptr<TestDevice> device = std::make_unique<TestDevice>();
    Layout layout;
    DeviceBuffer<float> normal, position, depth, a, b, c, sums;
    DeviceBuffer<std::int32_t> ids;
    DeviceBuffer<std::uint8_t> validity;

    Harness(int w, int h, int padding) {
        layout.width = w;
        layout.height = h;
        layout.padding = padding;
        layout.pitch = w + 2 * padding;
        layout.origin = padding * layout.pitch + padding;
        layout.planeSize = layout.pitch * (h + 2 * padding);
        std::size_t n = std::size_t(layout.planeSize);
        for (auto* buffer : {&normal, &position, &a, &b, &c}) {
            *buffer = DeviceBuffer<float>(*device, 3 * n);
            device->fill(buffer->data(), 0, buffer->bytes());
        }
        depth = DeviceBuffer<float>(*device, n);
        device->fill(depth.data(), 0, depth.bytes());
        sums = DeviceBuffer<float>(*device, 7 * n);
        device->fill(sums.data(), 0, sums.bytes());
        ids = DeviceBuffer<std::int32_t>(*device, n);
        device->fill(ids.data(), 0xff, ids.bytes());
        validity = DeviceBuffer<std::uint8_t>(*device, n);
        // A flat wall facing the camera, one object.
        Planes3 nrm = planes(normal), pos = planes(position);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                int i = layout.index(x, y);
                nrm.store(i, make3(0, 0, -1));
                pos.store(i, make3(float(x), float(y), 5.0f));
                depth.data()[i] = 5.0f;
                ids.data()[i] = 0;
            }
    }
    // Another zero-filled padded buffer of `count` planes.
    DeviceBuffer<float> buffer(int count) {
        DeviceBuffer<float> b(*device, std::size_t(count) * std::size_t(layout.planeSize));
        device->fill(b.data(), 0, b.bytes());
        return b;
    }
    PlaneSet planeSet(const DeviceBuffer<float>& buffer) const {
        return {buffer.data(), layout.planeSize};
    }
    Planes3 planes(const DeviceBuffer<float>& buffer) const {
        return {buffer.data(), layout.planeSize};
    }
    PlaneSet sumPlanes() const { return {sums.data(), layout.planeSize}; }
    // Row pass then column pass, as the Denoiser runs them.
    void accumulate(float alpha, float k, int radius) {
        int w = layout.width, h = layout.height;
        ASSERT_LE(radius, kNarrowWindow);
        device->launch(ColorRowSumsKernel{gbuffer(), planes(a), sumPlanes(), radius}, w, h);
        device->launch(AccumulateKernel{gbuffer(), sumPlanes(), planes(a), planes(b),
                                        validity.data(), planes(c), alpha, k, radius},
                       w, h);
    }
    void removeOutliers(int radius, float k) {
        int w = layout.width, h = layout.height;
        ASSERT_LE(radius, kNarrowWindow);
        device->launch(LuminanceRowSumsKernel{gbuffer(), planes(a), sumPlanes(), radius}, w, h);
        device->launch(OutlierKernel{gbuffer(), sumPlanes(), planes(a), planes(b), radius, k}, w,
                       h);
    }
    GBufferView gbuffer() const {
        return {layout, planes(normal), planes(position), depth.data(), ids.data(), {}, ids.data()};
    }
    // Every pixel of `p` from `next`: values in [offset, offset + 1).
    void fillRandom(const Planes3& p, UnitRandom& next, float offset = 0.0f) const {
        for (int y = 0; y < layout.height; ++y)
            for (int x = 0; x < layout.width; ++x) {
                float r = next(), g = next(), b = next();
                p.store(layout.index(x, y), make3(offset + r, offset + g, offset + b));
            }
    }
    // The caller's interleaved RGB as a modulated kernel wrote it: `result` times the albedo at
    // every pixel, within 4 ulp (relative 0: `result` from the same instantiation) or `relative`
    // (from another instantiation, which the compiler may sum in another order).
    void expectModulatedOutput(const Planes3& result, const Planes3& albedo,
                               const std::vector<float>& rgb, float relative = 0.0f) const {
        for (int y = 0; y < layout.height; ++y)
            for (int x = 0; x < layout.width; ++x) {
                auto i = layout.index(x, y);
                Float3 f = result.load(i), a = albedo.load(i);
                const float* out = &rgb[std::size_t(3 * (y * layout.width + x))];
                const float expected[3] = {f.x * a.x, f.y * a.y, f.z * a.z};
                for (int c = 0; c < 3; ++c) {
                    if (relative == 0.0f)
                        EXPECT_FLOAT_EQ(out[c], expected[c]) << x << ", " << y;
                    else
                        EXPECT_NEAR(out[c], expected[c], relative * std::fabs(expected[c]))
                            << x << ", " << y;
                }
            }
    }
    // Every pixel of `buffer`'s first three planes is `v` (a kernel left them alone).
    void expectAll(const DeviceBuffer<float>& buffer, Float3 v) const {
        for (int y = 0; y < layout.height; ++y)
            for (int x = 0; x < layout.width; ++x) {
                Float3 p = planes(buffer).load(layout.index(x, y));
                EXPECT_TRUE(p.x == v.x && p.y == v.y && p.z == v.z) << x << ", " << y;
            }
    }
    void setAll(const DeviceBuffer<float>& buffer, Float3 v) {
        for (int y = 0; y < layout.height; ++y)
            for (int x = 0; x < layout.width; ++x) planes(buffer).store(layout.index(x, y), v);
    }
};

}  // namespace rtd
