// Penumbra: global illumination with radiance cascades. The one header to include.
#pragma once

#include "penumbra/compare.hpp"
#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"
#include "penumbra/render.hpp"
#include "penumbra/scene.hpp"
#include "penumbra/version.hpp"
