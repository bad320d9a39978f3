// Values the command line spells in its own way: sizes in bytes and grid sizes.
#pragma once

#include <cstdint>
#include <string>

// "512M", "8G", "1.5GiB", or a plain number of bytes (K, M, G and KiB, MiB, GiB are powers of
// 1024). False for anything else, for less than one byte, and for sizes that do not fit 64 bits.
bool parse_bytes(const std::string& text, std::uint64_t& bytes);

// "WxH" with positive integers (no signs, no spaces, no overflow of int).
bool parse_grid_size(const std::string& text, int& width, int& height);
