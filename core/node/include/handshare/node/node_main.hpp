#pragma once
/// The shared shape of every node's main(): parse options, build, run, and map exceptions to
/// exit codes (2: bad option, 1: any other error), with the error printed once to stderr.
#include <functional>

#include "handshare/common/options.hpp"
#include "handshare/common/session_options.hpp"

namespace handshare::node {

/// Declares --domain, --session (required), --duration, --qos, --peers and --security.
void DeclareSessionOptions(common::Options& options);
/// Reads them back after parsing (resolving the --peers names); throws common::OptionError for a
/// bad value.
common::SessionOptions ReadSessionOptions(const common::Options& options);

/// Runs body(options) after parsing; returns the process exit code.
int RunNodeMain(int argc, const char* const argv[], common::Options& options,
                const std::function<int(const common::Options&)>& body);

}  // namespace handshare::node
