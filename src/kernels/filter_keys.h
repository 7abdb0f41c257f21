// The edge-aware filters' tap keys where objects are not kept apart (GBufferView::filterKey):
// 0 on every object and -1 on background, so that the filters' one comparison per tap (key equal
// to the centre's) takes any object's taps and no background's. Where objects are kept apart
// the object IDs serve as the keys and this pass does not run.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct FilterKeys {
    Layout layout;
    const std::int32_t* objectId;
    std::int32_t* key;  // its border stays -1 (the buffer is filled with -1 once)

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        key[i] = objectId[i] >= 0 ? 0 : -1;
    }
};
using FilterKeysKernel = FilterKeys;

}  // namespace rtd
