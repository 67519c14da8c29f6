#include "lsgd/options.h"

#include <charconv>
#include <cmath>
#include <set>
#include <system_error>

#include "internal/check.h"
#include "internal/numbers.h"

namespace lsgd {

std::string format_real(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  std::string text = ec == std::errc() ? std::string(buffer, end) : internal::concat(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

namespace internal {

void throw_out_of_range(const std::string& key, const std::string& value, double lo, double hi,
                        bool lo_open, bool integer, const std::string& unit) {
  const std::string range =
      integer ? concat("[", static_cast<std::int64_t>(lo), ", ", static_cast<std::int64_t>(hi), "]")
              : concat(lo_open ? "(" : "[", lo, ", ", hi, "]");
  throw_invalid(key, " = ", value, " is out of range: must be in ", range, unit.empty() ? "" : " ",
                unit);
}

std::string number_text(double value) { return concat(value); }

void throw_bad_option_text(const std::string& key, const std::string& text,
                           const std::string& expected) {
  throw_invalid(key, " = '", text, "' is not ", expected);
}

namespace {

using internal::parses_as;

}  // namespace

bool parse_integer_text(const std::string& text, std::int64_t& value) {
  return parses_as(text, value);
}

bool parse_real_text(const std::string& text, double& value) {
  static const std::set<std::string> kInf = {".inf", ".Inf", ".INF", "+.inf", "+.Inf", "+.INF"};
  static const std::set<std::string> kNegInf = {"-.inf", "-.Inf", "-.INF"};
  static const std::set<std::string> kNan = {".nan", ".NaN", ".NAN"};
  if (kInf.count(text)) {
    value = std::numeric_limits<double>::infinity();
  } else if (kNegInf.count(text)) {
    value = -std::numeric_limits<double>::infinity();
  } else if (kNan.count(text)) {
    value = std::numeric_limits<double>::quiet_NaN();
  } else {
    return parses_as(text, value);
  }
  return true;
}

}  // namespace internal
}  // namespace lsgd
