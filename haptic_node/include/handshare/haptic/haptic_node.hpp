#pragma once
/// A haptic node: one user at one device. The haptic loop runs on its own thread; this class
/// is the bridge thread around it: it joins the session, publishes the device state at viewer
/// rate and the loop statistics at 1 Hz, exchanges contact sets and body states with the peers
/// as they come (woken by the haptic step and the readers), and prints the loop statistics at
/// exit.
#include <array>
#include <chrono>
#include <string>

#include "handshare/common/session_options.hpp"

namespace handshare::haptic {

struct HapticNodeConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string user;
  std::string device = "sim";                    // sim, hiro, replay or plugin:PATH.so[:ARGS]
  std::array<double, 3> device_origin_m{0.0, -0.05, 0.12};  // plugin: where the device frame's origin is in W
  double device_scale = 1.0;                     // plugin: p_W = origin + scale p_D
  double device_deadline_s = 0.0005;             // plugin: a read or command slower than this is a fault
  std::string script;                            // sim: hand script file ("" = default motion)
  std::string replay_file;                       // replay: device-state log (a --trace file)
  bool replay_loop = false;                      // replay: start over at the end
  std::string hiro_config;                       // hiro: device geometry (assets/devices/hiro2.json)
  std::string cache_dir;                         // compliance caches ("" = world::DefaultCacheDir())
  double rate_Hz = 1000.0;
  double publish_Hz = 100.0;                     // device state for viewers (60-120 Hz)
  double deadband_weber = 0.10;                  // contact-set deadband (session/contact_deadband.hpp); 0: off
  bool coupling_passivity = true;                // passivity controller on the peers' contacts (contact/coupling_passivity.hpp); false: observe only
  bool paced_streams = true;                     // streams no faster than read (session/stream_rates.hpp); false: every tick
  double rejoin_after_s = 15.0;                  // no world server heard this long after joining: join again; 0: never
  std::string trace_file;                        // CSV of every published device state
  std::string dump_dir;                          // this node's field of each touched deformable ("" = none)
  bool coupling_on_wake = true;                  // contact sets and object states between ticks, woken by the haptic step and the readers; false: only at the bridge's ticks (as before; bench/net compares)
  std::string coupling_trace_file;               // every contact set written, taken and first used, with its times (bench/net; "" = none)
};

class HapticNode {
 public:
  explicit HapticNode(HapticNodeConfig config);
  int Run();

 private:
  HapticNodeConfig config_;
};

}  // namespace handshare::haptic
