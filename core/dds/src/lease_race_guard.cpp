// A guard against a race in Fast DDS 2.9.1 (Debian 12) that aborts a process when a peer leaves.
//
// Each remote participant has a lease timer. When it fires, the event thread runs
// PDP::check_remote_participant_liveliness, which takes the discovery mutex and asserts that the
// proxy it checks still names a participant. When the peer leaves (its DATA(p[UD]) arrives), a
// receive thread runs PDP::remove_remote_participant, which ends, under the same mutex, by
// cancelling the timer and clearing the proxy (GUID unknown) into the pool. Cancelling does not
// stop a callback that has already started: one that started just before, and reaches the mutex
// just after, finds a cleared proxy still marked for lease checks and fails the assertion
// (assertions are on in Debian's build). The abort (`session.scale`, at exit under load 13,
// when all 17 participants leave at once) can strike any node whenever a peer leaves; upstream's
// current code has the same check.
//
// The guard: a cleared proxy describes no participant, so it is not lease-checked. This file
// defines ParticipantProxyData::clear, which the executable exports in place of the library's
// (the library calls it through its PLT); it runs the library's own clear and then unmarks the
// lease check. A late callback then finds nothing to check. The proxy is marked again when the
// pool hands it to a new participant (PDP::add_participant_proxy_data), and a new proxy starts
// unmarked, so the mark now follows what the proxy holds. remove_remote_participant clears under
// the discovery mutex that the callback reads it under.
//
// tests: LeaseRace.* (core/dds/test/lease_race_test.cpp), whose helper widens the callback's
// window and aborts without this guard, in about a second.
#include "lease_race_guard.hpp"

#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>

#include "library_override.hpp"

namespace {

constexpr const char* kClearSymbol = "_ZN8eprosima8fastrtps4rtps20ParticipantProxyData5clearEv";

using ClearFn = void (*)(eprosima::fastrtps::rtps::ParticipantProxyData*);

// Without the library's clear a proxy would keep its last participant: LibraryDefinition stops.
ClearFn LibraryClear() {
  static const ClearFn library = reinterpret_cast<ClearFn>(
      handshare::dds::detail::LibraryDefinition(kClearSymbol, "ParticipantProxyData::clear"));
  return library;
}

}  // namespace

namespace eprosima::fastrtps::rtps {

void ParticipantProxyData::clear() {
  LibraryClear()(this);
  should_check_lease_duration = false;
}

}  // namespace eprosima::fastrtps::rtps

namespace handshare::dds::detail {

bool LeaseRaceGuardActive() { return OverrideInEffect(kClearSymbol, reinterpret_cast<void*>(LibraryClear())); }

}  // namespace handshare::dds::detail
