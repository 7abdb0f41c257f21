// The B3-spline kernel (1/16, 1/4, 3/8, 1/4, 1/16) of the A-Trous filters, by tap offset in
// units of the stride: both filters put its log2 inside the weight's exponent (no
// multiplication per tap).
#pragma once

#include "core/host_device.h"

namespace rtd {

// log2 of the spline's value at offset -2..2.
RTD_HOST_DEVICE constexpr float log2B3(int offset) {
    return offset == 0 ? -1.4150375f : (offset == 1 || offset == -1) ? -2.0f : -4.0f;
}
// log2 of the 5x5 kernel's value at (dx, dy), the product of the two.
RTD_HOST_DEVICE constexpr float log2B3(int dx, int dy) {
    return log2B3(dx) + log2B3(dy);
}
// The 5x5 kernel's centre value, (3/8)^2.
constexpr float kB3Centre = 0.375f * 0.375f;

}  // namespace rtd
