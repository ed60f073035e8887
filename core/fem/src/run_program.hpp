#pragma once
// Running an external program (tetgen, ccx) as a separate process, never linking it: both are
// GPL. Offline only (setup and tools), never from the haptic thread.

#include <filesystem>
#include <string>
#include <vector>

namespace handshare::fem::detail {

/// Runs args[0] (looked up in PATH) in `cwd` with stdout and stderr into `log`, stdin from
/// /dev/null; returns its exit code (128 + signal if it was killed).
/// @throws FemError if it cannot be started (naming `package` to install when it is missing).
int RunProgram(const std::vector<std::string>& args, const std::filesystem::path& cwd,
               const std::filesystem::path& log, const std::string& package);

/// The last max_chars characters of a file (for error messages), "..." first if cut.
std::string Tail(const std::filesystem::path& file, std::size_t max_chars);

}  // namespace handshare::fem::detail
