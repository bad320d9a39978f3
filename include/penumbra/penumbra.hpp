// Penumbra: global illumination with radiance cascades. The one header to include.
//
// Dimension-free: errors, images, files, image comparison. The 2D world ("flatland") is in
// penumbra::flatland: scenes, methods, rendering, its results written and compared.
#pragma once

#include "penumbra/compare.hpp"
#include "penumbra/error.hpp"
#include "penumbra/flatland/compare.hpp"
#include "penumbra/flatland/io.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"
#include "penumbra/version.hpp"
