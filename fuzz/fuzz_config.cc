// libFuzzer target: lsgd::io::parse_config on arbitrary text. Only lsgd::Error
// (InvalidArgument / IoError / FormatError) may escape; any other exception
// escapes the target and libFuzzer reports it, as it does a crash or a
// sanitizer finding. A config that parses must also pass check() and survive
// to_yaml -> parse_config.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "lsgd/error.h"
#include "lsgd/io/config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  lsgd::DetectorOptions options;
  try {
    options = lsgd::io::parse_config(text, "fuzz.yaml");
  } catch (const lsgd::Error&) {
    return 0;  // rejected with a message: the promised behaviour
  }
  // Accepted options are valid and round-trip through YAML.
  options.check();
  const lsgd::DetectorOptions again = lsgd::io::parse_config(lsgd::io::to_yaml(options), "rt");
  if (lsgd::io::to_yaml(again) != lsgd::io::to_yaml(options)) std::abort();
  return 0;
}
