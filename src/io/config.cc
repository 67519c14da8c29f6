#include "lsgd/io/config.h"

#include <algorithm>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "internal/check.h"
#include "internal/names.h"
#include "internal/numbers.h"
#include "lsgd/error.h"
#include "lsgd/io/files.h"
#include "lsgd/io/sequence.h"
#include "lsgd/limits.h"

namespace lsgd::io {
namespace {

using internal::concat;

// ---------------------------------------------------------------- errors

std::string at_line(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null() || mark.line < 0) return {};
  return concat(" (line ", mark.line + 1, ")");
}

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar: {
      // A long value is shown by its start, control characters escaped: a
      // message is one line.
      return concat(node.Tag() == "!" ? "the quoted string '" : "'",
                    internal::shown_value(node.Scalar()), "'");
    }
    default:
      return "an undefined value";
  }
}

[[noreturn]] void wrong_type(const std::string& source, const std::string& key,
                             const YAML::Node& node, const std::string& expected) {
  throw FormatError(
      concat(source, ": '", key, "' must be ", expected, ", got ", describe(node), at_line(node)));
}

// ---------------------------------------------------------------- scalars

// A YAML scalar usable as a number: plain (not quoted) and not null.
bool is_plain_scalar(const YAML::Node& node) { return node.IsScalar() && node.Tag() != "!"; }

using internal::parse_number;

std::int64_t read_int64(const YAML::Node& node, const std::string& source, const std::string& key,
                        std::int64_t lo, std::int64_t hi) {
  if (!is_plain_scalar(node)) wrong_type(source, key, node, "an integer");
  std::int64_t value = 0;
  const std::errc ec = parse_number(node.Scalar(), value);
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && (value < lo || value > hi))) {
    throw InvalidArgument(concat(source, ": '", key, "' = ", node.Scalar(),
                                 " does not fit an integer in [", lo, ", ", hi, "]",
                                 at_line(node)));
  }
  if (ec != std::errc()) wrong_type(source, key, node, "an integer");
  return value;
}

// YAML's spellings of infinity and NaN (.inf, -.Inf, .NAN, ...).
bool parse_special_double(const std::string& text, double& value) {
  static const std::set<std::string> kInf = {".inf", ".Inf", ".INF", "+.inf", "+.Inf", "+.INF"};
  static const std::set<std::string> kNegInf = {"-.inf", "-.Inf", "-.INF"};
  static const std::set<std::string> kNan = {".nan", ".NaN", ".NAN"};
  if (kInf.count(text))
    value = std::numeric_limits<double>::infinity();
  else if (kNegInf.count(text))
    value = -std::numeric_limits<double>::infinity();
  else if (kNan.count(text))
    value = std::numeric_limits<double>::quiet_NaN();
  else
    return false;
  return true;
}

double read_double(const YAML::Node& node, const std::string& source, const std::string& key) {
  if (!is_plain_scalar(node)) wrong_type(source, key, node, "a number");
  double value = 0;
  if (parse_special_double(node.Scalar(), value)) return value;
  const std::errc ec = parse_number(node.Scalar(), value);
  if (ec == std::errc::result_out_of_range) {
    throw InvalidArgument(concat(source, ": '", key, "' = ", node.Scalar(),
                                 " is out of the range of a double", at_line(node)));
  }
  if (ec != std::errc()) wrong_type(source, key, node, "a number");
  return value;
}

std::string read_string(const YAML::Node& node, const std::string& source, const std::string& key) {
  if (!node.IsScalar()) wrong_type(source, key, node, "a string");
  return node.Scalar();
}

// ---------------------------------------------------------------- maps

using Reader = std::function<void(const YAML::Node& value, const std::string& key)>;

struct Field {
  std::string name;
  Reader read;
};

std::string known_names(const std::vector<Field>& fields) {
  std::string out;
  for (const Field& f : fields) out += concat(out.empty() ? "" : ", ", f.name);
  return out;
}

std::string join_key(const std::string& prefix, const std::string& name) {
  return prefix.empty() ? name : concat(prefix, ".", name);
}

// Reads every key of the map `node` with the matching field; a null node (an
// empty section) keeps every value. Unknown, duplicate and non-scalar keys
// are FormatErrors naming the full key.
void read_map(const YAML::Node& node, const std::string& source, const std::string& prefix,
              const std::vector<Field>& fields) {
  if (node.IsNull()) return;
  if (!node.IsMap()) {
    if (prefix.empty()) {
      throw FormatError(concat(source, ": the document must be a map of sections (",
                               known_names(fields), "), got ", describe(node), at_line(node)));
    }
    wrong_type(source, prefix, node, concat("a map with keys ", known_names(fields)));
  }
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const YAML::Node& key_node = entry.first;
    if (!key_node.IsScalar()) wrong_type(source, join_key(prefix, "<key>"), key_node, "a name");
    const std::string key = join_key(prefix, key_node.Scalar());
    if (!seen.insert(key_node.Scalar()).second) {
      throw FormatError(concat(source, ": duplicate key '", key, "'", at_line(key_node)));
    }
    const Field* field = nullptr;
    for (const Field& f : fields) {
      if (key_node.Scalar() == f.name) field = &f;
    }
    if (field == nullptr) {
      std::vector<std::string> names;
      for (const Field& f : fields) names.push_back(f.name);
      const std::string guess = internal::nearest(key_node.Scalar(), names);
      throw FormatError(concat(source, ": unknown key '", key, "'",
                               guess.empty() ? std::string() : "; did you mean '" + join_key(prefix, guess) + "'?",
                               " (known: ", known_names(fields), ")", at_line(key_node)));
    }
    field->read(entry.second, key);
  }
}

// ---------------------------------------------------------------- sections

using Table = OptionTable<DetectorOptions>;

// Reads one option's value with the checks of its kind (the range is
// DetectorOptions::check()'s).
void read_value(const OptionField<DetectorOptions>& f, const YAML::Node& v,
                const std::string& source, const std::string& key, DetectorOptions& o) {
  switch (f.kind) {
    case OptionKind::kInteger:
      f.set_integer(o, read_int64(v, source, key, f.type_min, f.type_max));
      return;
    case OptionKind::kReal:
      f.set_real(o, read_double(v, source, key));
      return;
    case OptionKind::kChoice: {
      const std::string text = read_string(v, source, key);
      try {
        f.set_choice(o, text);
      } catch (const InvalidArgument& e) {  // names the value and what is accepted
        throw FormatError(concat(source, ": '", key, "': ", e.what(), at_line(v)));
      }
      return;
    }
  }
}

// Reads the map at `prefix` ("" for the document, "search", "search.nodes"):
// its keys are the next parts of the option keys below prefix, each an
// option or a section.
void read_section(const YAML::Node& node, const std::string& source, const std::string& prefix,
                  DetectorOptions& o) {
  const Table& table = DetectorOptions::fields();
  const std::string below = prefix.empty() ? "" : prefix + ".";
  std::vector<Field> fields;
  for (const OptionField<DetectorOptions>& f : table) {
    if (f.name.compare(0, below.size(), below) != 0) continue;
    const std::string rest = f.name.substr(below.size());
    const std::string part = rest.substr(0, rest.find('.'));
    bool seen = false;
    for (const Field& g : fields) seen = seen || part == g.name;
    if (seen) continue;
    const std::string full = below + part;
    if (part == rest) {
      fields.push_back({part, [&source, &o, &f](const YAML::Node& v, const std::string& k) {
                          read_value(f, v, source, k, o);
                        }});
    } else {
      fields.push_back({part, [&source, &o, full](const YAML::Node& v, const std::string&) {
                          read_section(v, source, full, o);
                        }});
    }
  }
  read_map(node, source, prefix, fields);
}

void read_root(const YAML::Node& root, const std::string& source, DetectorOptions& o) {
  read_section(root, source, "", o);
}

// Counts parser events, before yaml-cpp builds any node: the documents
// (below) and the nodes. A detector config has about a hundred nodes; a
// 1 MB flow sequence of empty items ("[,,,...]") has a million, which
// yaml-cpp's nodes took 550 MB and 1.5 s to hold before lsgd read the first
// key.
class DocumentCounter : public YAML::EventHandler {
 public:
  // More nodes than a config can have, by far.
  static constexpr std::int64_t kMaxNodes = 10'000;
  explicit DocumentCounter(const std::string& source) : source_(source) {}
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& at, YAML::anchor_t) override { node(at); }
  void OnAlias(const YAML::Mark& at, YAML::anchor_t) override { node(at); }
  void OnScalar(const YAML::Mark& at, const std::string&, YAML::anchor_t, const std::string&) override {
    node(at);
  }
  void OnSequenceStart(const YAML::Mark& at, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    node(at);
    open(at);
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& at, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    node(at);
    open(at);
  }
  void OnMapEnd() override { --depth_; }

 private:
  // Nested deeper than a config can be: refused here, before yaml-cpp's own
  // limit (500 levels, reported as "bad file") and before its recursion
  // needs more stack than a small thread has.
  static constexpr int kMaxDepth = 64;
  void open(const YAML::Mark& at) {
    if (++depth_ > kMaxDepth) {
      throw FormatError(concat(source_, ": YAML nested more than ", kMaxDepth, " levels deep (line ",
                               at.line + 1, "): a detector config is 3 levels deep; is this the right file?"));
    }
  }
  int depth_ = 0;
  void node(const YAML::Mark& at) {
    if (++nodes_ > kMaxNodes) {
      throw FormatError(concat(source_, ": more than ", kMaxNodes, " YAML nodes (line ", at.line + 1,
                               "): a detector config has about a hundred; is this the right file?"));
    }
  }
  std::string source_;
  std::int64_t nodes_ = 0;
};

std::vector<YAML::Node> load_documents(const std::string& text, const std::string& source) {
  try {
    // yaml-cpp < 0.8.1 (Debian 12 ships 0.7) loops forever in LoadAll, growing
    // memory, on some malformed streams such as "," (yaml-cpp issue #1040,
    // fixed by PR #1319). Every document takes at least one byte, so more
    // documents than bytes + 1 means that loop: reject it before LoadAll.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentCounter counter(source);
    for (std::size_t documents = 0; parser.HandleNextDocument(counter);) {
      if (++documents > text.size() + 1) {
        throw FormatError(concat(source, ": invalid YAML: the parser makes no progress (",
                                 documents, " documents from ", text.size(), " bytes)"));
      }
    }
    return YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    // A NUL byte is no YAML text: yaml-cpp said "unknown escape character:
    // \x0a" of a file that holds no escape.
    if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
      throw FormatError(concat(source, ": invalid YAML: a NUL byte on line ",
                               1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n'),
                               " (a binary file, or UTF-16 without a byte-order mark?): a config is UTF-8 text"));
    }
    const std::string line = e.mark.is_null() ? "" : concat(" (line ", e.mark.line + 1, ")");
    throw FormatError(concat(source, ": invalid YAML: ", e.msg, line));
  }
}

// YAML's line breaks are LF, CRLF and a lone CR (YAML 1.2, 5.4); yaml-cpp
// takes the first two only (a classic-Mac config was one line: "unknown key
// 'search:  min_gap'"), so a lone CR is read as LF, as every text file here.
std::string with_lf_line_breaks(const std::string& text) {
  if (text.find('\r') == std::string::npos) return text;
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\r') {
      out += text[i];
    } else if (i + 1 >= text.size() || text[i + 1] != '\n') {
      out += '\n';
    }
  }
  return out;
}

}  // namespace

DetectorOptions parse_config(const std::string& yaml_text, const std::string& source,
                             const DetectorOptions& base) {
  const std::string name = source.empty() ? "<config>" : source;
  const std::vector<YAML::Node> documents = load_documents(with_lf_line_breaks(yaml_text), name);
  if (documents.size() > 1) {
    throw FormatError(concat(name, ": expected one YAML document, got ", documents.size()));
  }
  DetectorOptions options = base;
  if (!documents.empty()) {
    try {
      read_root(documents.front(), name, options);
    } catch (const YAML::Exception& e) {  // not expected: every access is checked
      throw FormatError(concat(name, ": invalid config: ", e.msg));
    }
  }
  try {
    options.check();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(concat(name, ": ", e.what()));
  }
  return options;
}

DetectorOptions load_config(const std::string& path, const DetectorOptions& base) {
  check_input_file(path, "config", kMaxConfigBytes);
  // A read error is an error, not an empty config (the defaults).
  const std::vector<unsigned char> bytes = read_file(path, "config", kMaxConfigBytes);
  return parse_config(std::string(bytes.begin(), bytes.end()), path, base);
}

// ---------------------------------------------------------------- writing

std::string to_yaml(const DetectorOptions& options) {
  std::ostringstream out;
  std::vector<std::string> open;  // the sections the last key was in
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    std::vector<std::string> parts;
    std::stringstream key(f.name);
    for (std::string part; std::getline(key, part, '.');) parts.push_back(part);
    const std::size_t depth = parts.size() - 1;
    std::size_t same = 0;
    while (same < open.size() && same < depth && open[same] == parts[same]) ++same;
    open.resize(same);
    for (; open.size() < depth; open.push_back(parts[open.size()])) {
      out << std::string(2 * open.size(), ' ') << parts[open.size()] << ":\n";
    }
    out << std::string(2 * depth, ' ') << parts.back() << ": " << f.text(options);
    if (f.kind == OptionKind::kChoice) {
      std::string choices;
      for (const std::string& c : f.choices()) {
        choices += concat(choices.empty() ? "" : f.list ? ", " : " | ", c);
      }
      out << "  # " << (f.list ? "none or a list of " : "") << choices;
    } else if (!f.unit.empty()) {
      out << "  # " << f.unit;
    }
    out << "\n";
  }
  return out.str();
}

std::string options_reference(const DetectorOptions& options, bool markdown) {
  std::ostringstream out;
  if (markdown) {
    out << "# Detector options\n\n"
        << "Generated by `lsgd options --markdown` from the option tables (`lsgd/options.h`);\n"
        << "`tests/config_test.cc` fails when this file differs from them. Every key is\n"
        << "optional in a YAML config (`--config`); `--option KEY=VALUE` sets one on any\n"
        << "command. \"resume\": whether `lsgd run --database` accepts another value than\n"
        << "the stored one (\"no, with ...\": the stored value matters only then).\n\n"
        << "| key | default | unit | range | resume | what it does |\n"
        << "|---|---|---|---|---|---|\n";
  }
  for (const OptionField<DetectorOptions>& f : DetectorOptions::fields()) {
    std::string range;
    if (f.kind == OptionKind::kChoice) {
      for (const std::string& c : f.choices()) {
        range += concat(range.empty() ? "" : f.list ? ", " : markdown ? " \\| " : " | ", c);
      }
      range = (f.list ? "none or a comma-separated list of " : markdown ? "" : "one of ") + range;
    } else if (f.kind == OptionKind::kInteger) {
      range = concat("[", static_cast<std::int64_t>(f.lo), ", ", static_cast<std::int64_t>(f.hi), "]");
    } else {
      range = concat(f.lo_open ? "(" : "[", f.lo, ", ", f.hi, "]");
    }
    const std::string resume = f.resumable ? "yes" : f.when.empty() ? "no" : "no, " + f.when;
    if (markdown) {
      std::string doc = f.doc;
      for (std::size_t at = doc.find('|'); at != std::string::npos; at = doc.find('|', at + 2)) {
        doc.replace(at, 1, "\\|");
      }
      out << "| `" << f.name << "` | " << f.text(options) << " | " << f.unit << " | " << range
          << " | " << resume << " | " << doc << " |\n";
    } else {
      out << f.name << " = " << f.text(options) << (f.unit.empty() ? "" : " " + f.unit) << "  "
          << range << ": " << f.doc << "\n";
    }
  }
  return out.str();
}

}  // namespace lsgd::io
