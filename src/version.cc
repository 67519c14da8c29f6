#include "lsgd/version.h"

#include "lsgd_version.h"  // generated at build time (cmake/version.cmake)

namespace lsgd {

const char* version() { return LSGD_VERSION; }
const char* commit() { return LSGD_COMMIT; }

}  // namespace lsgd
