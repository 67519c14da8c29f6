#include "lsgd/io/config.h"

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
#include "lsgd/error.h"
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
    case YAML::NodeType::Scalar:
      return concat(node.Tag() == "!" ? "the quoted string '" : "'", node.Scalar(), "'");
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

// Parses the whole of `text` (an optional '+' is allowed) with from_chars.
template <typename T>
std::errc parse_number(std::string text, T& value) {
  if (!text.empty() && text[0] == '+') text.erase(0, 1);
  if (text.empty() || text[0] == '+' || text[0] == ' ') return std::errc::invalid_argument;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc()) return ec;
  return ptr == end ? std::errc() : std::errc::invalid_argument;
}

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

int read_int(const YAML::Node& node, const std::string& source, const std::string& key) {
  return static_cast<int>(read_int64(node, source, key, std::numeric_limits<int>::min(),
                                     std::numeric_limits<int>::max()));
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

// Parses an enum name with `parse` (which throws InvalidArgument), reporting
// a FormatError that names the key and the accepted names.
template <typename Enum, typename Parse>
Enum read_enum(const YAML::Node& node, const std::string& source, const std::string& key,
               Parse parse, const std::vector<Enum>& values) {
  const std::string name = read_string(node, source, key);
  try {
    return parse(name.c_str());
  } catch (const InvalidArgument&) {
    std::string known;
    for (Enum v : values) known += concat(known.empty() ? "" : ", ", to_string(v));
    wrong_type(source, key, node, concat("one of ", known));
  }
}

// ---------------------------------------------------------------- maps

using Reader = std::function<void(const YAML::Node& value, const std::string& key)>;

struct Field {
  const char* name;
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
      throw FormatError(concat(source, ": unknown key '", key, "' (known: ", known_names(fields),
                               ")", at_line(key_node)));
    }
    field->read(entry.second, key);
  }
}

// ---------------------------------------------------------------- sections

void read_segmentation(const YAML::Node& node, const std::string& source, SegmentationOptions& o) {
  read_map(node, source, "segmentation",
           {{"superpixel_size",
             [&](const YAML::Node& v, const std::string& k) {
               o.superpixel_size = read_int(v, source, k);
             }},
            {"iterations", [&](const YAML::Node& v,
                               const std::string& k) { o.iterations = read_int(v, source, k); }},
            {"intensity_scale",
             [&](const YAML::Node& v, const std::string& k) {
               o.intensity_scale = read_double(v, source, k);
             }},
            {"distance_scale", [&](const YAML::Node& v, const std::string& k) {
               o.distance_scale = read_double(v, source, k);
             }}});
}

void read_similarity(const YAML::Node& node, const std::string& source, SimilarityOptions& o) {
  read_map(node, source, "similarity",
           {{"metric", [&](const YAML::Node& v, const std::string& k) {
               o.metric = read_enum(v, source, k, parse_similarity_metric,
                                    std::vector<SimilarityMetric>{SimilarityMetric::kReference,
                                                                  SimilarityMetric::kL1,
                                                                  SimilarityMetric::kNormalizedL1});
             }}});
}

void read_descriptor(const YAML::Node& node, const std::string& source, DescriptorOptions& o) {
  read_map(node, source, "descriptor",
           {{"storage", [&](const YAML::Node& v, const std::string& k) {
               o.storage = read_enum(v, source, k, parse_histogram_storage,
                                     std::vector<HistogramStorage>{HistogramStorage::kExact,
                                                                   HistogramStorage::kCompact});
             }}});
}

void read_nodes(const YAML::Node& node, const std::string& source, DynamicNodeOptions& o) {
  read_map(
      node, source, "search.nodes",
      {{"threshold_0", [&](const YAML::Node& v,
                           const std::string& k) { o.threshold_0 = read_double(v, source, k); }},
       {"alpha",
        [&](const YAML::Node& v, const std::string& k) { o.alpha = read_double(v, source, k); }},
       {"beta",
        [&](const YAML::Node& v, const std::string& k) { o.beta = read_double(v, source, k); }}});
}

void read_search(const YAML::Node& node, const std::string& source, SearchOptions& o) {
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  read_map(
      node, source, "search",
      {{"mode",
        [&](const YAML::Node& v, const std::string& k) {
          o.mode = read_string(v, source, k);
          try {
            check_search_mode(o.mode);
          } catch (const InvalidArgument&) {
            wrong_type(source, k, v, concat("one of ", search_mode_names()));
          }
        }},
       {"min_gap", [&](const YAML::Node& v,
                       const std::string& k) { o.min_gap = read_int64(v, source, k, kMin, kMax); }},
       {"top_n",
        [&](const YAML::Node& v, const std::string& k) { o.top_n = read_int(v, source, k); }},
       {"nodes",
        [&](const YAML::Node& v, const std::string&) { read_nodes(v, source, o.nodes); }}});
}

void read_decision(const YAML::Node& node, const std::string& source, DecisionOptions& o) {
  read_map(node, source, "decision",
           {{"threshold",
             [&](const YAML::Node& v, const std::string& k) { o.threshold = read_double(v, source, k); }},
            {"geometric_bonus",
             [&](const YAML::Node& v, const std::string& k) {
               o.geometric_bonus = read_double(v, source, k);
             }},
            {"continuity_bonus",
             [&](const YAML::Node& v, const std::string& k) {
               o.continuity_bonus = read_double(v, source, k);
             }},
            {"continuity_inliers", [&](const YAML::Node& v, const std::string& k) {
               o.continuity_inliers = read_double(v, source, k);
             }}});
}

void read_temporal(const YAML::Node& node, const std::string& source, TemporalOptions& o) {
  read_map(node, source, "verification.temporal",
           {{"frames",
             [&](const YAML::Node& v, const std::string& k) { o.frames = read_int(v, source, k); }},
            {"long_frames",
             [&](const YAML::Node& v, const std::string& k) { o.long_frames = read_int(v, source, k); }},
            {"tolerance",
             [&](const YAML::Node& v, const std::string& k) { o.tolerance = read_int(v, source, k); }},
            {"agree",
             [&](const YAML::Node& v, const std::string& k) { o.agree = read_int(v, source, k); }}});
}

void read_geometric(const YAML::Node& node, const std::string& source, GeometricOptions& o) {
  read_map(
      node, source, "verification.geometric",
      {{"max_features",
        [&](const YAML::Node& v, const std::string& k) { o.max_features = read_int(v, source, k); }},
       {"min_side",
        [&](const YAML::Node& v, const std::string& k) { o.min_side = read_int(v, source, k); }},
       {"max_side",
        [&](const YAML::Node& v, const std::string& k) { o.max_side = read_int(v, source, k); }},
       {"ratio",
        [&](const YAML::Node& v, const std::string& k) { o.ratio = read_double(v, source, k); }},
       {"ransac_threshold",
        [&](const YAML::Node& v,
            const std::string& k) { o.ransac_threshold = read_double(v, source, k); }},
       {"min_inliers",
        [&](const YAML::Node& v, const std::string& k) { o.min_inliers = read_int(v, source, k); }},
       {"min_inlier_ratio", [&](const YAML::Node& v, const std::string& k) {
          o.min_inlier_ratio = read_double(v, source, k);
        }}});
}

void read_verification(const YAML::Node& node, const std::string& source,
                       VerificationOptions& o) {
  read_map(
      node, source, "verification",
      {{"stages",
        [&](const YAML::Node& v, const std::string& k) {
          const std::string text = read_string(v, source, k);
          try {
            parse_verification_stages(text, o);
          } catch (const InvalidArgument& e) {
            throw FormatError(concat(source, ": '", k, "': ", e.what(), at_line(v)));
          }
        }},
       {"max_candidates", [&](const YAML::Node& v,
                              const std::string& k) { o.max_candidates = read_int(v, source, k); }},
       {"temporal", [&](const YAML::Node& v,
                        const std::string&) { read_temporal(v, source, o.temporal_options); }},
       {"geometric", [&](const YAML::Node& v, const std::string&) {
          read_geometric(v, source, o.geometric_options);
        }}});
}

void read_root(const YAML::Node& root, const std::string& source, DetectorOptions& o) {
  read_map(
      root, source, "",
      {{"segmentation", [&](const YAML::Node& v,
                            const std::string&) { read_segmentation(v, source, o.segmentation); }},
       {"descriptor",
        [&](const YAML::Node& v, const std::string&) { read_descriptor(v, source, o.descriptor); }},
       {"similarity",
        [&](const YAML::Node& v, const std::string&) { read_similarity(v, source, o.similarity); }},
       {"search",
        [&](const YAML::Node& v, const std::string&) { read_search(v, source, o.search); }},
       {"verification", [&](const YAML::Node& v,
                            const std::string&) { read_verification(v, source, o.verification); }},
       {"decision",
        [&](const YAML::Node& v, const std::string&) { read_decision(v, source, o.decision); }}});
}

// Counts parser events; used to bound the number of documents (below).
class DocumentCounter : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

std::vector<YAML::Node> load_documents(const std::string& text, const std::string& source) {
  try {
    // yaml-cpp < 0.8.1 (Debian 12 ships 0.7) loops forever in LoadAll, growing
    // memory, on some malformed streams such as "," (yaml-cpp issue #1040,
    // fixed by PR #1319). Every document takes at least one byte, so more
    // documents than bytes + 1 means that loop: reject it before LoadAll.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentCounter counter;
    for (std::size_t documents = 0; parser.HandleNextDocument(counter);) {
      if (++documents > text.size() + 1) {
        throw FormatError(concat(source, ": invalid YAML: the parser makes no progress (",
                                 documents, " documents from ", text.size(), " bytes)"));
      }
    }
    return YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    const std::string line = e.mark.is_null() ? "" : concat(" (line ", e.mark.line + 1, ")");
    throw FormatError(concat(source, ": invalid YAML: ", e.msg, line));
  }
}

// ---------------------------------------------------------------- writing

// "exhaustive | nodes": the registered search modes, for the YAML comment.
std::string mode_choices() {
  std::string out;
  for (const SearchMode& m : search_modes()) out += concat(out.empty() ? "" : " | ", m.name);
  return out;
}

// Shortest decimal text that parses back to exactly `value`, always with a
// '.' or exponent so it reads as a float; YAML spellings for inf and NaN.
std::string format_double(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  std::string text = ec == std::errc() ? std::string(buffer, end) : concat(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

}  // namespace

DetectorOptions parse_config(const std::string& yaml_text, const std::string& source,
                             const DetectorOptions& base) {
  const std::string name = source.empty() ? "<config>" : source;
  const std::vector<YAML::Node> documents = load_documents(yaml_text, name);
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
  std::error_code ec;
  check_input_file(path, "config", kMaxConfigBytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const bool missing = !std::filesystem::exists(path, ec);
    throw IoError(concat("cannot read config '", path, "'", missing ? ": it does not exist" : ""));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IoError(concat("cannot read config '", path, "'"));
  return parse_config(text.str(), path, base);
}

std::string to_yaml(const DetectorOptions& options) {
  const SegmentationOptions& seg = options.segmentation;
  const SearchOptions& search = options.search;
  const VerificationOptions& v = options.verification;
  const GeometricOptions& geo = v.geometric_options;
  std::ostringstream out;
  out << "segmentation:\n"
      << "  superpixel_size: " << seg.superpixel_size << "  # S_p, pixels\n"
      << "  iterations: " << seg.iterations << "\n"
      << "  intensity_scale: " << format_double(seg.intensity_scale) << "\n"
      << "  distance_scale: " << format_double(seg.distance_scale) << "\n"
      << "descriptor:\n"
      << "  storage: " << to_string(options.descriptor.storage)
      << "  # exact (16-bit, 256 bins) | compact (8-bit, 128 bins)\n"
      << "similarity:\n"
      << "  metric: " << to_string(options.similarity.metric)
      << "  # reference | l1 | normalized_l1\n"
      << "search:\n"
      << "  mode: " << search.mode << "  # " << mode_choices() << "\n"
      << "  min_gap: " << search.min_gap << "  # frames\n"
      << "  top_n: " << search.top_n << "\n"
      << "  nodes: {threshold_0: " << format_double(search.nodes.threshold_0)
      << ", alpha: " << format_double(search.nodes.alpha)
      << ", beta: " << format_double(search.nodes.beta) << "}\n"
      << "verification:\n"
      << "  stages: " << verification_stages(v) << "  # none | temporal | geometric | "
      << "temporal,geometric\n"
      << "  max_candidates: " << v.max_candidates << "\n"
      << "  temporal: {frames: " << v.temporal_options.frames
      << ", long_frames: " << v.temporal_options.long_frames
      << ", tolerance: " << v.temporal_options.tolerance
      << ", agree: " << v.temporal_options.agree << "}\n"
      << "  geometric: {max_features: " << geo.max_features << ", min_side: " << geo.min_side
      << ", max_side: " << geo.max_side
      << ", ratio: " << format_double(geo.ratio)
      << ", ransac_threshold: " << format_double(geo.ransac_threshold)
      << ", min_inliers: " << geo.min_inliers
      << ", min_inlier_ratio: " << format_double(geo.min_inlier_ratio) << "}\n"
      << "decision:\n"
      << "  threshold: " << format_double(options.decision.threshold) << "\n"
      << "  geometric_bonus: " << format_double(options.decision.geometric_bonus) << "\n"
      << "  continuity_bonus: " << format_double(options.decision.continuity_bonus) << "\n"
      << "  continuity_inliers: " << format_double(options.decision.continuity_inliers) << "\n";
  return out.str();
}

}  // namespace lsgd::io
