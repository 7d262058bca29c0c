// The program's version and the commit it was built from (cmake/Version.cmake
// writes them at build time): `cellray --version`, the bench's JSON.
#pragma once

namespace cr {

const char* Version();      // "0.1.0"
const char* BuildCommit();  // `git describe --always --dirty` of the built tree, or "unknown"

}  // namespace cr
