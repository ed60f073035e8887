#pragma once
/// The shared shape of every node's main(): parse options, build, run, and map exceptions to
/// exit codes (2: bad option, 1: any other error), with the error printed once to stderr.
#include <functional>

#include "handshare/common/options.hpp"

namespace handshare::common {

/// Runs body(options) after parsing; returns the process exit code.
int RunNodeMain(int argc, const char* const argv[], Options& options,
                const std::function<int(const Options&)>& body);

}  // namespace handshare::common
