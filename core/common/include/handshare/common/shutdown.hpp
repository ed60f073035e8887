#pragma once
/// SIGINT/SIGTERM handling for every node: the handler only sets a flag; the node's loops
/// poll it and return, so destructors run and the DDS participant (and its shared-memory
/// segments) is deleted cleanly.
#include <chrono>

namespace handshare::common {

/// Installs the handlers (idempotent). Call once at the start of main().
void InstallShutdownHandlers();
/// True once SIGINT or SIGTERM arrived, or RequestShutdown() was called.
bool ShutdownRequested() noexcept;
/// Lets code (tests, --duration timers) end the node the same way a signal does.
void RequestShutdown() noexcept;
/// Sleeps for d, waking early (within about 5 ms) on a shutdown request.
/// @returns false if shutdown was requested.
bool SleepUnlessShutdown(std::chrono::nanoseconds d);

}  // namespace handshare::common
