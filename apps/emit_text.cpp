#include "emit_text.h"

#include <iostream>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

namespace qm3d::app {

void emit_text(const std::string& text, const std::string& output) {
  if (output.empty()) {
    std::cout << text << std::flush;
    if (!std::cout) throw InputError("stdout: write failed");
    return;
  }
  write_file_atomically(output, [&](std::ostream& out) { out << text; });
}

}  // namespace qm3d::app
