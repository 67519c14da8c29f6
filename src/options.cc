#include "lsgd/options.h"

#include <charconv>
#include <cmath>
#include <set>
#include <system_error>

#include "internal/check.h"
#include "internal/numbers.h"

namespace lsgd {

std::string shortest_text(double value) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return ec == std::errc() ? std::string(buffer, end) : internal::concat(value);
}

std::string format_real(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  std::string text = shortest_text(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

namespace internal {

std::string shown_value(const std::string& text) {
  constexpr std::size_t kShown = 64;
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < kShown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == 0) {
      out += "\\0";
    } else if (c < 0x20 || c == 0x7F) {
      out += concat("\\x", "0123456789abcdef"[c >> 4], "0123456789abcdef"[c & 15]);
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kShown) out += concat("... (", text.size(), " bytes)");
  return out;
}

namespace {

[[noreturn]] void throw_bad_option_text(const std::string& key, const std::string& text,
                                        const std::string& expected) {
  throw_invalid(key, " = '", shown_value(text), "' is not ", expected);
}

}  // namespace

}  // namespace internal

void check_option_range(const std::string& key, double value, const std::string& text, double lo,
                        double hi, bool lo_open, bool integer, const std::string& unit) {
  using internal::concat;
  if ((lo_open ? value > lo : value >= lo) && value <= hi) return;  // NaN is out of every range
  const std::string range =
      integer ? concat("[", static_cast<std::int64_t>(lo), ", ", static_cast<std::int64_t>(hi), "]")
              : concat(lo_open ? "(" : "[", lo, ", ", hi, "]");
  internal::throw_invalid(key, " = ", internal::shown_value(text.empty() ? concat(value) : text),
                          " is out of range: must be in ", range, unit.empty() ? "" : " ", unit);
}

std::int64_t parse_option_integer(const std::string& key, const std::string& text, std::int64_t lo,
                                  std::int64_t hi) {
  std::int64_t v = 0;
  if (internal::parses_as(text, v) && v >= lo && v <= hi) return v;
  // Digits alone are an integer beyond the option's type (or int64), not "not an integer".
  const std::size_t sign = !text.empty() && (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (text.size() > sign && text.find_first_not_of("0123456789", sign) == std::string::npos) {
    internal::throw_invalid(key, " = ", internal::shown_value(text),
                            " is out of range: far beyond the values it takes");
  }
  internal::throw_bad_option_text(key, text, "an integer");
}

double parse_option_real(const std::string& key, const std::string& text) {
  static const std::set<std::string> kInf = {".inf", ".Inf", ".INF", "+.inf", "+.Inf", "+.INF"};
  static const std::set<std::string> kNegInf = {"-.inf", "-.Inf", "-.INF"};
  static const std::set<std::string> kNan = {".nan", ".NaN", ".NAN"};
  if (kInf.count(text)) return std::numeric_limits<double>::infinity();
  if (kNegInf.count(text)) return -std::numeric_limits<double>::infinity();
  if (kNan.count(text)) return std::numeric_limits<double>::quiet_NaN();
  double v = 0;
  if (!internal::parses_as(text, v)) internal::throw_bad_option_text(key, text, "a number");
  return v;
}

}  // namespace lsgd
