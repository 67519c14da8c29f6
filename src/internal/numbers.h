// Whole-text number parsing, the one place every reader of numbers in text
// (option values, YAML scalars, ground-truth and detection files, dataset
// options) goes through.
#pragma once

#include <charconv>
#include <string_view>
#include <system_error>

namespace lsgd::internal {

// Parses all of `text` as a T with std::from_chars (locale-independent): one
// optional leading '+', no spaces, nothing after the number.
// std::errc::result_out_of_range when it does not fit T,
// std::errc::invalid_argument for anything else that is not a number.
template <typename T>
std::errc parse_number(std::string_view text, T& value) {
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  if (text.empty() || text[0] == '+' || text[0] == ' ') return std::errc::invalid_argument;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc()) return ec;
  return ptr == end ? std::errc() : std::errc::invalid_argument;
}

// True when all of `text` is a T (parse_number without the reason).
template <typename T>
bool parses_as(std::string_view text, T& value) {
  return parse_number(text, value) == std::errc();
}

}  // namespace lsgd::internal
