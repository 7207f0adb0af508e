#include "qm3d/common/version.h"

namespace qm3d {

const char* git_commit() {
  // The commit the library was built from (cmake/GitCommit.cmake writes it at every build).
  return
#include "git_commit.inc"
      ;
}

}  // namespace qm3d
