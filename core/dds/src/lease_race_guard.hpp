// The guard against Fast DDS 2.9.1's lease-check race (lease_race_guard.cpp).
#pragma once

namespace handshare::dds::detail {

// True when this process's Fast DDS calls the guarded ParticipantProxyData::clear (the
// executable's definition took the place of the library's). Participant warns once when not.
bool LeaseRaceGuardActive();

}  // namespace handshare::dds::detail
