// Byte counts for people: what a message about a budget or a size prints.
#pragma once

#include <cstdint>
#include <string>

namespace cellwalk {

// "812 bytes", "7.5 KiB", "8.0 MiB", "1.3 GiB": one decimal, rounded to nearest, so a small
// budget never prints as "0 MiB" and a need never rounds below the budget it exceeds.
std::string byte_size_text(uint64_t bytes);

}  // namespace cellwalk
