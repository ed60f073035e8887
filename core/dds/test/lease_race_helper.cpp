// Helper of the LeaseRace tests (lease_race_test.cpp): participants that keep leaving while
// observers check their leases, with the lease check's window widened, so that Fast DDS 2.9.1's
// race (src/lease_race_guard.cpp) is met within about a second when nothing guards it.
//
// Built twice: lease_race_helper links handshare::dds and so has the guard;
// lease_race_helper_unguarded (HANDSHARE_UNGUARDED) links Fast DDS alone, as the control.
//
// usage: lease_race_helper DOMAIN SECONDS
// prints "guard active" or "guard absent", runs SECONDS, prints "survived N departures", exits 0.
#include <dlfcn.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/rtps/builtin/discovery/participant/PDP.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <memory>
#include <thread>
#include <vector>

#ifndef HANDSHARE_UNGUARDED
#include "../src/lease_race_guard.hpp"
#endif
#include "rtps_test_support.hpp"

namespace eprosima::fastrtps::rtps {

// The widening: the library's lease check, begun 3 ms late. The event thread has then started
// the callback (the timer can no longer be cancelled) but not yet taken the discovery mutex, as
// when it is preempted there on a busy machine.
void PDP::check_remote_participant_liveliness(ParticipantProxyData* remote) {
  using Fn = void (*)(PDP*, ParticipantProxyData*);
  static const Fn library = reinterpret_cast<Fn>(dlsym(
      RTLD_NEXT, "_ZN8eprosima8fastrtps4rtps3PDP35check_remote_participant_livelinessEPNS1_20ParticipantProxyDataE"));
  if (library == nullptr) {
    std::fprintf(stderr, "lease_race_helper: Fast DDS's check_remote_participant_liveliness not found\n");
    std::exit(2);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(3));
  library(this, remote);
}

}  // namespace eprosima::fastrtps::rtps

namespace fdds = eprosima::fastdds::dds;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s DOMAIN SECONDS\n", argv[0]);
    return 2;
  }
  const int domain = std::atoi(argv[1]);
  const double seconds = std::atof(argv[2]);
#ifdef HANDSHARE_UNGUARDED
  std::printf("guard absent\n");
#else
  std::printf("guard %s\n", handshare::dds::detail::LeaseRaceGuardActive() ? "active" : "absent");
#endif
  std::fflush(stdout);

  auto* factory = fdds::DomainParticipantFactory::get_instance();
  // UDP only: the control aborts, and would leave shared-memory segments behind.
  fdds::DomainParticipantQos qos =
      handshare::dds::test_support::OnlyOver(std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>());
  // A 30 ms lease announced every 10 ms: each observer checks each peer about 30 times a second.
  qos.wire_protocol().builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(0, 30000000);
  qos.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod =
      eprosima::fastrtps::Duration_t(0, 10000000);

  std::vector<fdds::DomainParticipant*> observers;
  for (int i = 0; i < 3; ++i) {
    observers.push_back(factory->create_participant(domain, qos));
    if (observers.back() == nullptr) {
      std::fprintf(stderr, "lease_race_helper: could not create an observer on domain %d\n", domain);
      return 1;
    }
  }
  std::atomic<bool> stop{false};
  std::atomic<long> departures{0};
  std::atomic<bool> failed{false};
  std::vector<std::thread> peers;
  for (int i = 0; i < 4; ++i) {
    peers.emplace_back([&] {
      while (!stop) {
        fdds::DomainParticipant* p = factory->create_participant(domain, qos);
        if (p == nullptr) {
          failed = true;
          return;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(60));  // discovered, checked, then gone
        factory->delete_participant(p);
        ++departures;
      }
    });
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!failed && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  stop = true;
  for (auto& t : peers) t.join();
  for (auto* o : observers) factory->delete_participant(o);
  if (failed) {
    std::fprintf(stderr, "lease_race_helper: could not create a peer on domain %d\n", domain);
    return 1;
  }
  std::printf("survived %ld departures\n", departures.load());
  return 0;
}
