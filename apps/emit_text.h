// Where a command of the qm3d tool writes its output.
#pragma once

#include <string>

namespace qm3d::app {

/// Writes a command's output: to stdout (a failed write, e.g. a closed pipe, is an InputError) or,
/// atomically, to `output` when it is not empty.
void emit_text(const std::string& text, const std::string& output);

}  // namespace qm3d::app
