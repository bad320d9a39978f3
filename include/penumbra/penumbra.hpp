// Penumbra: global illumination with radiance cascades. The one header to include.
//
// Dimension-free: errors, images, files, image comparison. The 2D world ("flatland") is in
// penumbra::flatland: scenes, methods, rendering, its results written and compared. The 3D world
// ("spaceland") is in penumbra::spaceland: scenes with meshes, methods, the camera's image.
#pragma once

#include "penumbra/compare.hpp"
#include "penumbra/error.hpp"
#include "penumbra/flatland/compare.hpp"
#include "penumbra/flatland/io.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"
#include "penumbra/progress.hpp"
#include "penumbra/spaceland/field.hpp"
#include "penumbra/spaceland/io.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "penumbra/vec3.hpp"
#include "penumbra/version.hpp"
