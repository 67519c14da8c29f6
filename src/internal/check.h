// Validation helpers shared by the options structs: each throws
// InvalidArgument with a message naming the field, its value and the range.
#pragma once

#include <sstream>
#include <string>

#include "lsgd/error.h"

namespace lsgd::internal {

template <typename... Parts>
std::string concat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

template <typename... Parts>
[[noreturn]] void throw_invalid(const Parts&... parts) {
  throw InvalidArgument(concat(parts...));
}

// Checks lo <= value <= hi; `unit` is appended to the message ("pixels").
template <typename T>
void check_range(const char* field, T value, T lo, T hi, const char* unit = "") {
  if (!(value >= lo && value <= hi)) {  // also rejects NaN
    throw_invalid(field, " = ", value, " is out of range: must be in [", lo, ", ", hi, "]",
                  *unit ? " " : "", unit);
  }
}

// Checks lo < value <= hi (for strictly positive scales).
template <typename T>
void check_range_open_low(const char* field, T value, T lo, T hi, const char* unit = "") {
  if (!(value > lo && value <= hi)) {
    throw_invalid(field, " = ", value, " is out of range: must be in (", lo, ", ", hi, "]",
                  *unit ? " " : "", unit);
  }
}

// A value as a message shows it, on one line: control characters (a NUL)
// escaped, cut after 64 bytes with the length said (src/options.cc).
std::string shown_value(const std::string& text);

}  // namespace lsgd::internal
