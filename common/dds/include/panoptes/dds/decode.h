// SPDX-License-Identifier: Apache-2.0
// Decoding one received sample (its CDR payload) into a generated message type, and the reason it
// failed. Every typed reader of a Bus decodes through this (docs/hostile_input.md): a malformed
// sample from any participant on the bus is counted under its reason and dropped, never a crash.
// Free of Fast DDS (only Fast CDR and the generated types), so that the fuzz targets of
// tests/fuzz/ can run it without a participant.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace panoptes::dds {

enum class DecodeError {
  kNone,
  // The payload ends before the sample does: a truncated sample, or a string or sequence whose
  // length claims more bytes than arrived (an absurd length looks exactly like this).
  kTruncated,
  // The 4-byte encapsulation header names no CDR representation Fast CDR knows.
  kBadEncapsulation,
  // Shorter than the sample it decodes to: only a string without its terminating NUL does that.
  kUnterminatedString,
  // Decoding needed more memory than there is.
  kOutOfMemory,
  kOther,  // any other exception of the decoder
};

// The counter name of a failure ("cdr_truncated", ...), as reported in camera_status and
// estimator_status; "" for kNone.
std::string_view decode_error_name(DecodeError error);

// Decodes `size` bytes (encapsulation header included) into `message`. Never throws. On failure
// `message` holds whatever was decoded so far: the caller must drop it.
template <class T>
DecodeError decode_sample(const std::uint8_t* data, std::size_t size, T& message);

// The CDR of `message` as a writer sends it (encapsulation header included, little endian).
template <class T>
std::vector<std::uint8_t> encode_sample(const T& message);

// Counts by reason, shared by the readers of a Bus (thread-safe).
class ReceiveCounters {
 public:
  void note(std::string_view reason);
  std::map<std::string, std::uint64_t> snapshot() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::uint64_t, std::less<>> counts_;
};

}  // namespace panoptes::dds
