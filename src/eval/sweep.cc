#include "lsgd/eval/sweep.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "internal/check.h"
#include "lsgd/error.h"
#include "lsgd/io/config.h"

namespace lsgd::eval {
namespace {

using internal::concat;
using internal::throw_invalid;
using internal::shown_value;

constexpr std::size_t kMaxAxisValues = 10'000;
// Every configuration is a whole run of each dataset (seconds to minutes), and
// each is parsed and kept before the first run: a grid of 10,000 is days of
// runs already, and is checked in about a second; a million took minutes and
// gigabytes before it could start (docs/reliability.md).
constexpr std::size_t kMaxPoints = 10'000;
constexpr int kMaxDecimals = 9;

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t pos; (pos = text.find(separator, start)) != std::string::npos; start = pos + 1) {
    parts.push_back(text.substr(start, pos - start));
  }
  parts.push_back(text.substr(start));
  return parts;
}

bool is_word_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

// A value written into YAML as a plain scalar: only characters that cannot
// change the document's structure.
void check_scalar(const std::string& value, const std::string& context) {
  if (value.empty()) throw_invalid(context, ": empty value");
  for (char c : value) {
    if (!is_word_char(c) && c != '.' && c != '+' && c != '-' && c != ',') {
      throw_invalid(context, ": value '", shown_value(value), "' holds '", std::string(1, c),
                    "' (allowed: letters, digits and . _ + - ,)");
    }
  }
}

void check_key(const std::string& key, const std::string& context) {
  for (const std::string& part : split(key, '.')) {
    bool ok = !part.empty();
    for (char c : part) ok = ok && is_word_char(c);
    if (!ok) throw_invalid(context, ": '", shown_value(key), "' is not a dotted option name like search.mode");
  }
}

// Parses [+-]digits[.digits] (either digit run may be empty, not both) into
// its digits without the point ("-1.25" -> "-125") and its number of decimals.
bool parse_decimal(const std::string& text, std::string& digits, int& out_decimals) {
  std::size_t i = 0;
  const bool negative = !text.empty() && text[0] == '-';
  if (!text.empty() && (text[0] == '-' || text[0] == '+')) i = 1;
  digits.clear();
  int decimals = -1;
  for (; i < text.size(); ++i) {
    if (text[i] == '.' && decimals < 0) {
      decimals = 0;
    } else if (text[i] >= '0' && text[i] <= '9') {
      digits += text[i];
      if (decimals >= 0) ++decimals;
    } else {
      return false;
    }
  }
  out_decimals = decimals < 0 ? 0 : decimals;
  if (digits.empty() || out_decimals > kMaxDecimals) return false;
  if (negative) digits.insert(0, "-");
  return true;
}

// Scales the digit string of a number with `decimals` decimals to `target` decimals.
bool rescale(const std::string& digits, int decimals, int target, std::int64_t& out) {
  const std::string text = digits + std::string(static_cast<std::size_t>(target - decimals), '0');
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  constexpr std::int64_t kLimit = 1'000'000'000'000'000'000;  // 1e18: no overflow in b - a
  return ec == std::errc() && end == text.data() + text.size() && out < kLimit && out > -kLimit;
}

std::string format_decimal(std::int64_t scaled, int decimals) {
  const std::string sign = scaled < 0 ? "-" : "";
  std::string digits = std::to_string(scaled < 0 ? -scaled : scaled);
  if (decimals == 0) return sign + digits;
  if (digits.size() <= static_cast<std::size_t>(decimals)) {
    digits.insert(0, static_cast<std::size_t>(decimals) + 1 - digits.size(), '0');
  }
  digits.insert(digits.size() - static_cast<std::size_t>(decimals), ".");
  return sign + digits;
}

// Expands "a:b:step" exactly, in integer multiples of the finest decimal.
void expand_range(const std::string& item, const std::string& context,
                  std::vector<std::string>& values) {
  const std::vector<std::string> parts = split(item, ':');
  if (parts.size() != 3) throw_invalid(context, ": range '", shown_value(item), "' must be a:b:step");
  std::string digits[3];
  int places[3] = {0, 0, 0};
  int decimals = 0;
  for (int k = 0; k < 3; ++k) {
    if (!parse_decimal(trim(parts[k]), digits[k], places[k])) {
      throw_invalid(context, ": range '", shown_value(item), "': '", shown_value(trim(parts[k])),
                    "' is not a decimal number with at most ", kMaxDecimals, " decimals");
    }
    decimals = std::max(decimals, places[k]);
  }
  std::int64_t a = 0, b = 0, step = 0;
  if (!rescale(digits[0], places[0], decimals, a) || !rescale(digits[1], places[1], decimals, b) ||
      !rescale(digits[2], places[2], decimals, step)) {
    throw_invalid(context, ": range '", shown_value(item), "' has a number too large");
  }
  if (step == 0) throw_invalid(context, ": range '", shown_value(item), "' has a zero step");
  if ((b - a) != 0 && ((b - a) > 0) != (step > 0)) {
    throw_invalid(context, ": range '", shown_value(item), "' is empty: the step goes away from the end");
  }
  const std::int64_t count = (b - a) / step + 1;
  if (count > static_cast<std::int64_t>(kMaxAxisValues)) {
    throw_invalid(context, ": range '", shown_value(item), "' has ", count, " values (at most ", kMaxAxisValues,
                  ")");
  }
  for (std::int64_t i = 0; i < count; ++i) values.push_back(format_decimal(a + i * step, decimals));
}

// One section or value of the YAML written by sweep_yaml.
struct YamlNode {
  std::string name;
  std::string value;  // leaf value; empty for a section
  std::vector<YamlNode> children;
};

void insert(YamlNode& root, const std::string& key, const std::string& value) {
  YamlNode* node = &root;
  const std::vector<std::string> parts = split(key, '.');
  for (std::size_t i = 0; i < parts.size(); ++i) {
    YamlNode* child = nullptr;
    for (YamlNode& c : node->children) {
      if (c.name == parts[i]) child = &c;
    }
    const bool last = i + 1 == parts.size();
    if (child != nullptr && (last || !child->value.empty())) {
      throw_invalid("sweep: key '", key, "' conflicts with another key of the same sweep");
    }
    if (child == nullptr) {
      node->children.push_back({parts[i], last ? value : std::string(), {}});
      child = &node->children.back();
    }
    node = child;
  }
}

void write(const YamlNode& node, int depth, std::string& out) {
  for (const YamlNode& c : node.children) {
    out += std::string(static_cast<std::size_t>(2 * depth), ' ') + c.name + ":";
    if (c.children.empty()) {
      out += " " + c.value + "\n";
    } else {
      out += "\n";
      write(c, depth + 1, out);
    }
  }
}

// parse_config with any lsgd error turned into InvalidArgument (a bad sweep is a bad argument).
DetectorOptions parse_as_argument(const std::string& yaml, const std::string& source,
                                  const DetectorOptions& base) {
  try {
    return io::parse_config(yaml, source, base);
  } catch (const Error& e) {
    // Line numbers would point into the generated YAML, not into anything the user wrote.
    std::string message = e.what();
    const std::size_t at = message.rfind(" (line ");
    if (at != std::string::npos && message.back() == ')') message.erase(at);
    throw InvalidArgument(message);
  }
}

}  // namespace

SweepAxis parse_sweep_axis(const std::string& spec) {
  const std::string context = concat("sweep '", shown_value(spec), "'");
  const std::size_t eq = spec.find('=');
  if (eq == std::string::npos) throw_invalid(context, ": expected KEY=VALUES");
  SweepAxis axis;
  axis.spec = spec;
  axis.key = trim(spec.substr(0, eq));
  check_key(axis.key, context);
  const std::string list = spec.substr(eq + 1);
  const char separator = list.find(';') != std::string::npos ? ';' : ',';
  for (const std::string& raw : split(list, separator)) {
    const std::string item = trim(raw);
    if (item.find(':') != std::string::npos) {
      expand_range(item, context, axis.values);
    } else {
      check_scalar(item, context);
      axis.values.push_back(item);
    }
    if (axis.values.size() > kMaxAxisValues) {
      throw_invalid(context, ": more than ", kMaxAxisValues, " values");
    }
  }
  return axis;
}

std::string sweep_yaml(const std::vector<std::string>& keys,
                       const std::vector<std::string>& values) {
  if (keys.size() != values.size()) {
    throw_invalid("sweep_yaml: ", keys.size(), " keys but ", values.size(), " values");
  }
  YamlNode root;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string context = concat("sweep key '", shown_value(keys[i]), "'");
    check_key(keys[i], context);
    check_scalar(values[i], context);
    insert(root, keys[i], values[i]);
  }
  std::string out;
  write(root, 0, out);
  return out;
}

namespace {

// The grid as a whole, before any value is parsed: its size, and no window
// in the options it applies to.
void check_grid(const std::vector<SweepAxis>& axes, const DetectorOptions& base) {
  double all = 1;  // up to 10,000^axes: a double
  for (const SweepAxis& a : axes) all *= static_cast<double>(a.values.size());
  if (all > static_cast<double>(kMaxPoints)) {
    throw_invalid("sweep: ", all < 1e15 ? std::to_string(static_cast<std::int64_t>(all)) : shortest_text(all),
                  " configurations, more than the ", kMaxPoints,
                  " a sweep runs (each one is a whole run of every dataset): sweep fewer values");
  }
  // Each dataset has its own window (sweep_cells()): one in the options would
  // be dropped without a word.
  if (base.search.min_gap != DetectorOptions{}.search.min_gap) {
    throw_invalid("the sweep's options set search.min_gap = ", base.search.min_gap,
                  ": the window is set per dataset, by its spec NAME=...,MIN_GAP, so it would be ignored");
  }
}

// One axis, given the keys of the axes before it: a key swept once, not the
// window, each value parsed and given once.
void check_axis(const SweepAxis& axis, const std::vector<SweepAxis>& axes, const std::vector<std::string>& keys,
                const DetectorOptions& base) {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (keys[k] == axis.key) {
      throw_invalid("sweep '", shown_value(axis.spec), "': key '", axis.key, "' is already swept by '",
                    shown_value(axes[k].spec), "'");
    }
  }
  if (axis.values.empty()) throw_invalid("sweep '", shown_value(axis.spec), "': no values");
  // sweep_cells() gives each dataset its own window: a swept one would be
  // dropped without a word.
  if (axis.key == "search.min_gap") {
    throw_invalid("sweep '", shown_value(axis.spec), "': the window is set per dataset, by its spec "
                  "NAME=...,MIN_GAP (lsgd sweep --dataset), not swept");
  }
  // A value given twice, or twice spelt ("5,5.0"), ran the same
  // configuration twice: identical rows, as if the grid had more points.
  const OptionField<DetectorOptions>* field = find_option(DetectorOptions::fields(), axis.key);
  std::map<std::string, std::string> seen;  // the option's text -> the value that set it
  for (const std::string& value : axis.values) {
    const DetectorOptions o = parse_as_argument(
        sweep_yaml({axis.key}, {value}), concat("sweep '", shown_value(axis.spec), "' (value ", shown_value(value), ")"), base);
    const std::string text = field != nullptr ? field->text(o) : value;
    const auto [at, fresh] = seen.emplace(text, value);
    if (!fresh) {
      throw_invalid("sweep '", shown_value(axis.spec), "': the values '", shown_value(at->second), "' and '",
                    shown_value(value), "' both set ", axis.key, " = ", shown_value(text),
                    " (the same configuration twice, identical rows): give each value once");
    }
  }
}

// Every point of the cross product, the last axis turning fastest.
std::vector<SweepPoint> grid_points(const std::vector<SweepAxis>& axes, const std::vector<std::string>& keys,
                                    std::size_t total, const DetectorOptions& base) {
  std::vector<SweepPoint> points;
  points.reserve(total);
  std::vector<std::size_t> index(axes.size(), 0);
  for (std::size_t p = 0; p < total; ++p) {
    SweepPoint point;
    std::string label;
    for (std::size_t k = 0; k < axes.size(); ++k) {
      point.values.push_back(axes[k].values[index[k]]);
      label += concat(k ? ", " : "", keys[k], "=", point.values.back());
    }
    point.options =
        parse_as_argument(sweep_yaml(keys, point.values), concat("sweep point ", label), base);
    points.push_back(std::move(point));
    for (std::size_t k = axes.size(); k-- > 0;) {  // odometer: the last axis turns fastest
      if (++index[k] < axes[k].values.size()) break;
      index[k] = 0;
    }
  }
  return points;
}

// An option that applies in no configuration (search.nodes.beta in
// exhaustive mode, another descriptor's option, a disabled stage's) gives
// identical rows that read as "it does not matter": refused, saying when it
// applies.
void check_every_axis_applies(const std::vector<SweepAxis>& axes, const std::vector<SweepPoint>& points) {
  for (const SweepAxis& axis : axes) {
    const OptionField<DetectorOptions>* field = find_option(DetectorOptions::fields(), axis.key);
    if (field == nullptr || !field->applies) continue;
    const bool somewhere = std::any_of(points.begin(), points.end(),
                                       [&](const SweepPoint& p) { return field->applies(p.options); });
    if (!somewhere) {
      throw_invalid("sweep '", shown_value(axis.spec), "': ", axis.key, " has no effect in any configuration of the grid (it applies ",
                    field->when.empty() ? "under other options" : field->when,
                    "): set or sweep what it depends on too");
    }
  }
}

}  // namespace

std::vector<SweepPoint> expand_sweep(const std::vector<SweepAxis>& axes,
                                     const DetectorOptions& base) {
  check_grid(axes, base);  // the grid's size first: every value and point is parsed below
  std::vector<std::string> keys;
  std::size_t total = 1;
  for (const SweepAxis& axis : axes) {
    check_axis(axis, axes, keys, base);
    keys.push_back(axis.key);
    total *= axis.values.size();
  }
  std::vector<SweepPoint> points = grid_points(axes, keys, total, base);
  check_every_axis_applies(axes, points);
  return points;
}

SweepDataset parse_dataset_spec(const std::string& spec) {
  const std::string context = concat("dataset '", shown_value(spec), "'");
  const std::size_t eq = spec.find('=');
  if (eq == std::string::npos) {
    throw_invalid(context, ": expected NAME=SEQUENCE,GT,MIN_GAP or NAME=DIR,MIN_GAP");
  }
  SweepDataset d;
  d.name = spec.substr(0, eq);
  bool name_ok = !d.name.empty();
  for (char c : d.name) name_ok = name_ok && (is_word_char(c) || c == '.' || c == '-');
  if (!name_ok) throw_invalid(context, ": name '", shown_value(d.name), "' must be letters, digits, . _ -");
  std::vector<std::string> parts;
  std::vector<std::string> options;  // KEY=VALUE after the positional parts
  for (const std::string& part : split(spec.substr(eq + 1), ',')) {
    (part.find('=') != std::string::npos || !options.empty() ? options : parts).push_back(part);
  }
  std::vector<std::string> keys;
  for (const std::string& option : options) {
    const std::size_t at = option.find('=');
    if (at == std::string::npos || at == 0) {
      throw_invalid(context, ": '", shown_value(option), "' after the dataset options is not KEY=VALUE");
    }
    const std::string key = option.substr(0, at);
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) {
      throw_invalid(context, ": ", shown_value(key), " is given twice: give it once");
    }
    keys.push_back(key);
    try {
      set_dataset_option(d.sequence_options, d.gt_options, option.substr(0, at),
                         option.substr(at + 1));
    } catch (const InvalidArgument& e) {
      throw_invalid(context, ": ", e.what());
    }
  }
  try {
    d.sequence_options.check();
  } catch (const InvalidArgument& e) {
    throw_invalid(context, ": ", e.what());
  }
  if (parts.size() != 2 && parts.size() != 3) {
    throw_invalid(context, ": expected NAME=SEQUENCE,GT,MIN_GAP or NAME=DIR,MIN_GAP (",
                  parts.size(), " comma-separated parts after '=')");
  }
  for (const std::string& part : parts) {
    if (part.empty()) throw_invalid(context, ": empty part");
  }
  const std::string& gap = parts.back();
  const auto [end, ec] = std::from_chars(gap.data(), gap.data() + gap.size(), d.min_gap);
  if (ec != std::errc() || end != gap.data() + gap.size() || d.min_gap < 0) {
    throw_invalid(context, ": MIN_GAP '", gap, "' must be an integer >= 0 (frames)");
  }
  if (parts.size() == 2) {
    const std::filesystem::path dir(parts[0]);
    d.sequence = (dir / "sequence.txt").string();
    d.ground_truth = (dir / "groundtruth.txt").string();
  } else {
    d.sequence = parts[0];
    d.ground_truth = parts[1];
  }
  return d;
}

}  // namespace lsgd::eval
