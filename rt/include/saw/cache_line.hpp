// The cache-line size the project aligns shared atomics to (fixed: it is part of shared layouts).
#pragma once

#include <cstddef>

namespace saw {
inline constexpr std::size_t cache_line = 64;
}
