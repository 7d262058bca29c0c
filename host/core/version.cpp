#include "host/core/version.h"

#include "cellray_version.h"  // generated: cmake/Version.cmake

namespace cr {

const char* Version() { return CELLRAY_VERSION; }
const char* BuildCommit() { return CELLRAY_COMMIT; }

}  // namespace cr
