// The CPU launcher: rows spread over all cores by OpenMP; the kernel functor is inlined into the
// row loop so the compiler can vectorise it.
#pragma once

namespace rtd {

template <class Kernel>
void parallelFor2D(int width, int height, const Kernel& kernel) {
#pragma omp parallel for schedule(dynamic, 4)
    for (int y = 0; y < height; ++y) {
#pragma omp simd
        for (int x = 0; x < width; ++x) kernel(x, y);
    }
}

}  // namespace rtd
