// SPDX-License-Identifier: Apache-2.0
// Byte order and float formats of the three C3D processor types.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

#include "panoptes/formats/c3d.h"

namespace panoptes::c3d {

inline constexpr std::size_t kBlockBytes = 512;
inline constexpr std::uint8_t kParameterKey = 0x50;  // second byte of a C3D file
inline constexpr int kProcessorBase = 83;            // processor byte = 83 + type

inline std::uint16_t to_u16(const std::uint8_t* b, C3dProcessor processor) {
  if (processor == C3dProcessor::kMips) return static_cast<std::uint16_t>((b[0] << 8) | b[1]);
  return static_cast<std::uint16_t>(b[0] | (b[1] << 8));
}

inline float to_float(const std::uint8_t* b, C3dProcessor processor) {
  std::uint32_t bits = 0;
  if (processor == C3dProcessor::kMips) {
    bits = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) | (std::uint32_t{b[2]} << 8) | b[3];
    return std::bit_cast<float>(bits);
  }
  if (processor == C3dProcessor::kIntel) {
    bits = (std::uint32_t{b[3]} << 24) | (std::uint32_t{b[2]} << 16) | (std::uint32_t{b[1]} << 8) | b[0];
    return std::bit_cast<float>(bits);
  }
  // DEC (VAX F_floating): two little-endian 16-bit words, the one with sign and exponent first;
  // exponent bias 128 and the hidden bit worth 1/2, so the same bits read as IEEE are 4x the value.
  bits = (std::uint32_t{b[1]} << 24) | (std::uint32_t{b[0]} << 16) | (std::uint32_t{b[3]} << 8) | b[2];
  if ((bits & 0x7f800000u) == 0) return 0.0F;  // exponent 0: zero (or VAX's reserved operand)
  return std::bit_cast<float>(bits) / 4.0F;
}

inline void put_u16(std::uint8_t* b, std::uint16_t value) {
  b[0] = static_cast<std::uint8_t>(value & 0xff);
  b[1] = static_cast<std::uint8_t>(value >> 8);
}

inline void put_float(std::uint8_t* b, float value) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) b[i] = static_cast<std::uint8_t>((bits >> (8 * i)) & 0xff);
}

}  // namespace panoptes::c3d
