// What launchers read off a kernel's type to shape their work.
#pragma once

#include <type_traits>
#include <utility>

namespace rtd {

// A kernel with `int tapRowStride() const` reads rows y + k * stride, |k| <= 2 (an A-Trous
// level); launchers order or shape their work by it. In C++17 form: the CUDA back end's
// translation unit is C++17.
template <class Kernel, class = void>
inline constexpr bool kHasTapRowStride = false;
template <class Kernel>
inline constexpr bool
    kHasTapRowStride<Kernel, std::void_t<decltype(std::declval<const Kernel&>().tapRowStride())>> =
        true;

}  // namespace rtd
