// YAML configuration of the detector. Every key is optional (defaults are the
// DetectorOptions defaults); unknown keys, wrong types and out-of-range values
// are errors naming the file and key. The keys, with their defaults, units,
// ranges and documentation, are in docs/options.md (`lsgd options`), generated
// from the option tables (lsgd/options.h). A section is a YAML map:
//
//   search:
//     mode: nodes
//     nodes:
//       beta: 1.1
//   verification:
//     stages: temporal,geometric
#pragma once

#include <string>

#include "lsgd/detector.h"

namespace lsgd::io {

// Parses YAML text on top of `base` (keys not given keep base's values).
// `source` names the text in error messages (usually the file path). Throws
// FormatError for malformed YAML, unknown keys and wrong types, and
// InvalidArgument (via DetectorOptions::check) for out-of-range values, both
// naming source and key.
DetectorOptions parse_config(const std::string& yaml_text, const std::string& source,
                             const DetectorOptions& base = {});

// Reads and parses a config file. Throws IoError when it cannot be read.
DetectorOptions load_config(const std::string& path, const DetectorOptions& base = {});

// Writes every option as YAML that parse_config reads back to equal options.
std::string to_yaml(const DetectorOptions& options);

// The reference of every option (DetectorOptions::fields()): key, value in
// `options` (the defaults unless given), unit, range or choices, whether a
// resumed database may change it, and its line of documentation. Markdown is
// docs/options.md (a test keeps the two equal); otherwise one plain line
// per option.
std::string options_reference(const DetectorOptions& options = {}, bool markdown = true);

}  // namespace lsgd::io
