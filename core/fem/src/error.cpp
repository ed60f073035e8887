#include "handshare/fem/error.hpp"

#include <utility>

namespace handshare::fem {
namespace {

std::string FormatInputError(const std::string& file, std::size_t line, const std::string& field,
                             const std::string& what) {
  std::string msg;
  if (!file.empty()) {
    msg += file;
    if (line > 0) msg += ":" + std::to_string(line);
    msg += ": ";
  }
  if (!field.empty()) msg += "field '" + field + "': ";
  msg += what;
  return msg;
}

}  // namespace

InputError::InputError(std::string file, std::size_t line, std::string field,
                       const std::string& what)
    : FemError(FormatInputError(file, line, field, what)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)) {}

}  // namespace handshare::fem
