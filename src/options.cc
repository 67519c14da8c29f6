#include "lsgd/options.h"

#include <charconv>
#include <cmath>
#include <set>
#include <system_error>

#include "internal/check.h"
#include "internal/numbers.h"
#include "internal/option_tables.h"

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

namespace {
std::atomic<std::uint64_t> registered{0};
}  // namespace

std::uint64_t registrations() { return registered.load(); }
void count_registration() { registered.fetch_add(1); }

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
  const std::errc ec = internal::parse_number(text, v);
  if (ec == std::errc::result_out_of_range) {  // 1e309, 1e-400: a number, but not a double
    internal::throw_invalid(key, " = ", internal::shown_value(text),
                            " is out of range: beyond what a double holds");
  }
  if (ec != std::errc()) internal::throw_bad_option_text(key, text, "a number");
  return v;
}

void check_option_choice(const std::string& key, const std::string& value,
                         const std::vector<std::string>& choices) {
  std::string all;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    if (choices[k] == value) return;
    all += (k == 0 ? "" : k + 1 == choices.size() ? " or " : ", ") + choices[k];
  }
  internal::throw_bad_option_text(key, value, "one of " + all);
}

const std::string* OwnOptionValues::find(const std::string& key) const {
  const auto it = values_.find(key);
  return it == values_.end() ? nullptr : &it->second;
}

namespace {

bool is_option_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

// The default's text as the table writes it, checked like a value set.
std::string canonical_default(const OwnOption& o, const std::string& key) {
  switch (o.kind) {
    case OptionKind::kInteger: {
      const std::int64_t v = parse_option_integer(key, o.default_value,
                                                  std::numeric_limits<std::int64_t>::min(),
                                                  std::numeric_limits<std::int64_t>::max());
      check_option_range(key, static_cast<double>(v), o.default_value, o.lo, o.hi, o.lo_open, true,
                         o.unit);
      return std::to_string(v);
    }
    case OptionKind::kReal: {
      const double v = parse_option_real(key, o.default_value);
      check_option_range(key, v, "", o.lo, o.hi, o.lo_open, false, o.unit);
      return format_real(v);
    }
    case OptionKind::kChoice:
      check_option_choice(key, o.default_value, o.choices);
      return o.default_value;
  }
  return o.default_value;
}

const OwnOption& declared_option(const std::vector<OwnOption>& declared, const std::string& owner,
                                 const std::string& name, OptionKind kind) {
  for (const OwnOption& o : declared) {
    if (o.name != name) continue;
    if (o.kind != kind) {
      internal::throw_invalid(owner, ".", name, " is not an option of the kind asked for");
    }
    return o;
  }
  internal::throw_invalid(owner, " declares no option '", name, "'");
}

const std::string& own_text(const OwnOptionValues& values, const OwnOption& o,
                            const std::string& key) {
  const std::string* v = values.find(key);
  return v != nullptr ? *v : o.default_value;
}

}  // namespace

std::vector<OwnOption> checked_own_options(const std::vector<OwnOption>& options,
                                           const std::string& caller, const std::string& owner) {
  std::vector<OwnOption> out = options;
  for (std::size_t i = 0; i < out.size(); ++i) {
    OwnOption& o = out[i];
    const std::string key = owner + "." + o.name;
    if (!is_option_name(o.name)) {
      internal::throw_invalid(caller, ": ", owner, ": option name '", internal::shown_value(o.name),
                              "' must be 1 to 64 lower-case letters, digits or '_'");
    }
    for (std::size_t k = 0; k < i; ++k) {
      if (out[k].name == o.name) internal::throw_invalid(caller, ": ", owner, " declares '", o.name, "' twice");
    }
    if (o.doc.empty()) internal::throw_invalid(caller, ": ", key, " needs a line of documentation");
    if (o.kind == OptionKind::kChoice) {
      if (o.choices.empty()) internal::throw_invalid(caller, ": ", key, " needs its choices");
    } else if (!(o.lo <= o.hi)) {
      internal::throw_invalid(caller, ": ", key, " has an empty range [", o.lo, ", ", o.hi, "]");
    }
    try {
      o.default_value = canonical_default(o, key);
    } catch (const InvalidArgument& e) {
      internal::throw_invalid(caller, ": the default of ", e.what());
    }
  }
  return out;
}

std::int64_t own_integer(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                         const std::string& owner, const std::string& name) {
  const OwnOption& o = declared_option(declared, owner, name, OptionKind::kInteger);
  const std::string key = owner + "." + name;
  return parse_option_integer(key, own_text(values, o, key), std::numeric_limits<std::int64_t>::min(),
                              std::numeric_limits<std::int64_t>::max());
}

double own_real(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                const std::string& owner, const std::string& name) {
  const OwnOption& o = declared_option(declared, owner, name, OptionKind::kReal);
  const std::string key = owner + "." + name;
  return parse_option_real(key, own_text(values, o, key));
}

std::string own_choice(const OwnOptionValues& values, const std::vector<OwnOption>& declared,
                       const std::string& owner, const std::string& name) {
  const OwnOption& o = declared_option(declared, owner, name, OptionKind::kChoice);
  return own_text(values, o, owner + "." + name);
}

}  // namespace lsgd
