#pragma once
/// @file
/// Exceptions of the FEM library. They are thrown only from setup code (file readers,
/// precomputation, cache I/O, constructors); the real-time Solve() calls never throw and report a
/// status instead.

#include <cstddef>
#include <stdexcept>
#include <string>

namespace handshare::fem {

/// Base of every exception the FEM library throws: says what failed and where.
class FemError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input (a file or an argument). The message reads "FILE:LINE: field 'FIELD': WHAT"; the
/// parts that are unknown are left out (line 0 means "not tied to one line").
class InputError : public FemError {
 public:
  InputError(std::string file, std::size_t line, std::string field, const std::string& what);

  /// File name as given by the caller (empty when the input was not a file).
  const std::string& file() const noexcept { return file_; }
  /// 1-based line number; 0 when the error is not tied to one line.
  std::size_t line() const noexcept { return line_; }
  /// The field that was wrong, e.g. "node id" or "imposed[2].u_m".
  const std::string& field() const noexcept { return field_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string field_;
};

/// A compliance cache that cannot be used: missing, not a cache, other version, stale (built
/// for another mesh, material or fixed set), corrupt (checksum) or truncated.
class CacheError : public FemError {
 public:
  using FemError::FemError;
};

}  // namespace handshare::fem
