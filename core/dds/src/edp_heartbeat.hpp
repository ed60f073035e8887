// The discovery endpoints' repair timing (edp_heartbeat.cpp).
#pragma once

#include <chrono>

namespace handshare::dds::detail {

// What the endpoint-discovery writers of every participant in this process are given.
inline constexpr std::chrono::milliseconds kEdpHeartbeatPeriod{50};
inline constexpr std::chrono::milliseconds kEdpNackResponseDelay{5};

// True when this process's Fast DDS builds its endpoint-discovery writers with the times above
// (the executable's EDPSimple::set_builtin_writer_attributes took the place of the library's).
bool EdpHeartbeatShortened();

}  // namespace handshare::dds::detail
