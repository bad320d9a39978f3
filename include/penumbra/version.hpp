#pragma once

namespace penumbra {
inline constexpr const char* kVersion = "0.1.0";
}
