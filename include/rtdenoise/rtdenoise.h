// Umbrella header of the rtdenoise library.
#pragma once

#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "rtdenoise/image.h"
#include "rtdenoise/io.h"
#include "rtdenoise/settings.h"
