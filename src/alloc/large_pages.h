// large_pages.h: what the programs' operator new (large_pages.cpp) holds, for its tests.
#pragma once

#include <cstddef>

namespace hbil::alloc {

// Whether large_pages.cpp's operator new is in place (not under AddressSanitizer).
bool large_pages_active();
// The bytes of freed large blocks it keeps for reuse.
std::size_t cached_bytes();

}  // namespace hbil::alloc
