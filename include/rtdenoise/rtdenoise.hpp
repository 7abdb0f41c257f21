// Umbrella header of the rtdenoise C++ library (the denoiser). Files (EXR, PNG, sequences, video)
// are the rtdenoise_io library's: rtdenoise/io.h. The C API, the one with a stable ABI:
// rtdenoise/rtdenoise.h.
#pragma once

#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "rtdenoise/image.h"
#include "rtdenoise/settings.h"
