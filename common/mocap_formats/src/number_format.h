// SPDX-License-Identifier: Apache-2.0
// Fixed-point decimal text for the text writers (TRC, CSV): the value rounded to `decimals`
// places, written with integer arithmetic (std::to_chars with a precision is several times slower,
// and an export writes millions of numbers).
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>

namespace panoptes::formats {

inline void append_fixed(std::string& out, double value, int decimals) {
  static constexpr std::int64_t kPowers[] = {1,      10,      100,      1000,      10000,
                                             100000, 1000000, 10000000, 100000000, 1000000000};
  const std::int64_t scale = kPowers[decimals];
  // Beyond 9e9 units the scaled value could overflow: fall back to the library.
  if (!(std::abs(value) < 9e9)) {
    char buffer[400];
    const auto result =
        std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed, decimals);
    out.append(buffer, result.ptr);
    return;
  }
  const std::int64_t scaled = std::llround(value * static_cast<double>(scale));
  if (scaled < 0) out += '-';
  const std::uint64_t magnitude = static_cast<std::uint64_t>(scaled < 0 ? -scaled : scaled);
  char buffer[32];
  auto result = std::to_chars(buffer, buffer + sizeof(buffer), magnitude / static_cast<std::uint64_t>(scale));
  out.append(buffer, result.ptr);
  if (decimals == 0) return;
  out += '.';
  std::uint64_t fraction = magnitude % static_cast<std::uint64_t>(scale);
  char digits[16];
  for (int i = decimals - 1; i >= 0; --i) {
    digits[i] = static_cast<char>('0' + fraction % 10);
    fraction /= 10;
  }
  out.append(digits, static_cast<std::size_t>(decimals));
}

}  // namespace panoptes::formats
