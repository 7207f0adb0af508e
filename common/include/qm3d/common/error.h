// Typed errors shared by every qm3d module.
//
// Every failure throws one of these with a message that names the file or value at fault.
// The command-line tool maps them to exit codes (see apps/): InputError and FormatError and
// NumericError are "bad input" (exit 2); anything else is an internal error (exit 3).
#pragma once

#include <stdexcept>
#include <string>

namespace qm3d {

/// Base class of every error qm3d throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file or directory cannot be found, opened or read (missing, a directory, no permission).
class InputError : public Error {
 public:
  using Error::Error;
};

/// A file was read but its content is malformed (bad header, truncated, out-of-range index,
/// missing colours, unknown extension ...).
class FormatError : public Error {
 public:
  using Error::Error;
};

/// The input is well-formed but the metric cannot be computed on it (empty mesh, zero-size
/// bounding box, non-finite coordinates ...).
class NumericError : public Error {
 public:
  using Error::Error;
};

}  // namespace qm3d
