// SPDX-License-Identifier: Apache-2.0
// The fast path of the JSONL records (private to panoptes_io, docs/contracts.md "JSON Lines"):
// writing numbers without building a JSON document, and reading lines exactly as this library
// writes them (compact, keys in the documented order) without one. A line of any other shape
// (spaces, another key order, a missing optional key, an unknown key, a bad value) makes the
// reader give up, and the full parser reads it with its error messages: the fast path never
// accepts a line the full parser would refuse, nor reads a value differently.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

namespace panoptes::jsonl_fast {

// A double as the full writer (nlohmann's dump) writes it, in value if not in text: the shortest
// text that reads back to the same double, ".0" after an integral one, null for NaN and infinities.
inline void append_number(std::string& out, double value) {
  if (!std::isfinite(value)) {
    out += "null";
    return;
  }
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  const std::string_view text(buffer, static_cast<std::size_t>(result.ptr - buffer));
  out += text;
  if (text.find_first_of(".e") == std::string_view::npos) out += ".0";
}

inline void append_number(std::string& out, std::int64_t value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

// `key` as it is written (quotes, colon and any comma before it), then the number.
template <class Number>
void append_field(std::string& out, std::string_view key, Number value) {
  out += key;
  append_number(out, value);
}

// `key` as it is written (as append_field), then `count` (> 0) numbers as a JSON array.
template <typename Number>
void append_list(std::string& out, const char* key, const Number* values, int count) {
  out += key;
  for (int i = 0; i < count; ++i) {
    out += i == 0 ? '[' : ',';
    append_number(out, values[i]);
  }
  out += ']';
}

// A character a string may hold as it is, both ways: printable ASCII other than the quote and the
// backslash (any other string is written and read by the full JSON library, with its escapes).
inline bool plain_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u >= 0x20 && u < 0x80 && c != '"' && c != '\\';
}

// Reads one line left to right; every method returns false (and the caller gives up) at the
// first character it does not expect.
class Cursor {
 public:
  explicit Cursor(std::string_view text) : text_(text) {}

  bool literal(std::string_view expected) {
    if (text_.substr(at_, expected.size()) != expected) return false;
    at_ += expected.size();
    return true;
  }
  bool peek(char c) const { return at_ < text_.size() && text_[at_] == c; }
  bool at_end() const { return at_ == text_.size(); }

  // A JSON integer (no fraction, no exponent) that fits in T.
  template <class T>
  bool integer(T& out) {
    const std::string_view token = number_token(false);
    if (token.empty()) return false;
    const auto result = std::from_chars(token.data(), token.data() + token.size(), out);
    return result.ec == std::errc() && result.ptr == token.data() + token.size();
  }

  // Any JSON number, read correctly rounded (as the full parser does).
  bool number(double& out) {
    const std::string_view token = number_token(true);
    if (token.empty()) return false;
    const auto result = std::from_chars(token.data(), token.data() + token.size(), out);
    return result.ec == std::errc() && result.ptr == token.data() + token.size();
  }

  // [n0,n1,...] with exactly `count` numbers.
  template <class Out>
  bool numbers(Out& out, int count) {
    if (!literal("[")) return false;
    for (int i = 0; i < count; ++i) {
      double value = 0.0;
      if ((i > 0 && !literal(",")) || !number(value)) return false;
      out[i] = value;
    }
    return literal("]");
  }

  // A string without escapes (anything with a backslash or a control character is left to the full parser).
  bool plain_string(std::string_view& out) {
    if (!literal("\"")) return false;
    const std::size_t start = at_;
    while (at_ < text_.size() && text_[at_] != '"') {
      if (!plain_char(text_[at_])) return false;
      ++at_;
    }
    if (at_ == text_.size()) return false;
    out = text_.substr(start, at_ - start);
    ++at_;
    return true;
  }

 private:
  // The longest JSON number at the cursor (-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?), consumed;
  // empty if there is none, or if it has a fraction or exponent and `real` is false.
  std::string_view number_token(bool real) {
    const std::size_t start = at_;
    std::size_t i = at_;
    auto digits = [&] {
      const std::size_t from = i;
      while (i < text_.size() && text_[i] >= '0' && text_[i] <= '9') ++i;
      return i - from;
    };
    if (i < text_.size() && text_[i] == '-') ++i;
    if (i < text_.size() && text_[i] == '0') {
      ++i;
    } else if (digits() == 0) {
      return {};
    }
    if (i < text_.size() && text_[i] == '.') {
      ++i;
      if (!real || digits() == 0) return {};
    }
    if (i < text_.size() && (text_[i] == 'e' || text_[i] == 'E')) {
      ++i;
      if (i < text_.size() && (text_[i] == '+' || text_[i] == '-')) ++i;
      if (!real || digits() == 0) return {};
    }
    at_ = i;
    return text_.substr(start, i - start);
  }

  std::string_view text_;
  std::size_t at_ = 0;
};

}  // namespace panoptes::jsonl_fast
