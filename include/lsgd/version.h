// The library's version and the commit it was built from.
#pragma once

namespace lsgd {

// "0.1.0": the project version (CMakeLists.txt).
const char* version();
// The git commit the library was built from ("git describe --always --dirty",
// e.g. "05e5e35a1b2c" or "05e5e35a1b2c-dirty"), "unknown" outside a checkout.
const char* commit();

}  // namespace lsgd
