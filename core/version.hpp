// The program's version as recorded in checkpoints and printed by --version: the project version and,
// in a git checkout, the revision it was built from (generated at build time by cmake/version_info.cmake).
#pragma once

namespace mpsfsi {

/// E.g. "0.1.0+g0123456789ab" (".dirty" appended when the build had uncommitted changes to tracked files).
const char* code_version();

}  // namespace mpsfsi
