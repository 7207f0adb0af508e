// Typed errors shared by every qm3d module.
//
// Every failure throws one of these with a message that names the file or value at fault.
// The command-line tool maps them to exit codes (see apps/): InputError and FormatError and
// NumericError are "bad input" (exit 2); anything else is an internal error (exit 3).
#pragma once

#include <cstddef>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

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

/// A computation refused up front because it would not fit in memory (its estimate exceeds what
/// the process may allocate). A std::bad_alloc, so that it reads as "out of memory" everywhere
/// (exit 3 in the tool, MemoryError in Python), with the estimate in what().
class MemoryLimitError : public std::bad_alloc {
 public:
  explicit MemoryLimitError(std::string message) : message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// The bytes this process may allocate: the smaller of the physical memory and the address-space
/// limit (ulimit -v); 0 when neither is known.
std::size_t memory_limit_bytes();

}  // namespace qm3d
