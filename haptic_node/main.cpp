// haptic_node: one user at one haptic device (HIRO II, simulated, or a desk's mouse and keyboard) joining a session.
#include "handshare/common/data_dir.hpp"
#include "handshare/node/node_main.hpp"
#include "handshare/haptic/haptic_node.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "haptic_node", "Joins a handshare session with a haptic device and runs the haptic loop.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("user", "U", "user name, unique in the session", std::nullopt, true)
      .Value("device", "KIND",
             "device driver: sim, hiro (simulated HIRO II plant), replay, desk (a person at the mouse and keyboard of "
             "'graphics_node --view user:U --input desk'), or plugin:PATH.so[:ARGS] (a lab's device through the C ABI "
             "of handshare/device_plugin.h); docs/devices.md", "sim")
      .Value("device-origin", "X,Y,Z", "plugin: where the device's workspace centre is in the world [m]", "0,-0.05,0.12")
      .Value("device-scale", "S", "plugin: world metres per device metre", "1")
      .Value("device-deadline-us", "US", "plugin: a read or command taking longer is a device fault", "500")
      .Value("hiro-config", "FILE", "hiro: device geometry",
             (handshare::common::AssetsDir() / "devices" / "hiro2.json").string())
      .Value("cache", "DIR", "compliance cache of the deformable objects (default: ~/.cache/handshare)", "")
      .Value("script", "FILE", "sim, hiro: the (simulated) user's hand script (examples in " +
                                   handshare::common::HandScriptsDir().string() + ")", "")
      .Value("replay", "FILE", "replay: device-state log to play back (a --trace file)", "")
      .Flag("replay-loop", "replay: start over at the end of the log")
      .Value("rate", "HZ", "haptic loop rate", "1000")
      .Value("publish-rate", "HZ", "device state rate for viewers", "100")
      .Value("deadband", "FRACTION",
             "Weber fraction of the contact-set deadband: a set goes out when a force or imposed "
             "displacement changed by more than this share (0: every bridge tick)", "0.1")
      .Value("streams", "MODE",
             "paced: device states at the fastest viewer's frame rate, contact sets at the world server's tick "
             "unless a peer touches the same object; full: both at the publish rate",
             "paced")
      .Value("coupling-passivity", "MODE",
             "on: a passivity controller holds back what a peer's late contact would put into a shared deformable "
             "beyond what the peer put in, and closes the lag at the fade's rate; off: observe only", "on")
      .Value("coupling", "MODE",
             "woken: a contact set leaves after the haptic step that made it and a peer's reaches the next haptic step "
             "(the bridge woken by the step and the readers); polled: both wait for the bridge's next tick (as before "
             "2026-12-02; for before/after measurements)", "woken")
      .Value("trace", "FILE", "write every published device state to a CSV file", "")
      .Value("dump-deformation", "DIR", "write this node's field of each deformable it touches to DIR/<object>.json, "
             "at most every 100 ms (to compare with the world server's)", "")
      .Value("rejoin-after", "SEC",
             "join again with a new participant when no world server was heard this long after joining "
             "(a secured join whose handshake never finished; 0: never)", "15");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::haptic::HapticNodeConfig c;
    c.where = handshare::node::ReadSessionOptions(o);
    c.user = o.GetString("user");
    c.device = o.GetString("device");
    if (c.device != "sim" && c.device != "replay" && c.device != "hiro" && c.device != "desk" &&
        c.device.rfind("plugin:", 0) != 0) {
      throw handshare::common::OptionError("option --device: '" + c.device +
                                           "' is not available (this build has: sim, hiro, replay, desk, plugin:PATH.so[:ARGS])");
    }
    c.device_origin_m = o.GetVector3("device-origin", 10.0);
    c.device_scale = o.GetDouble("device-scale", 1e-3, 1e3);
    c.device_deadline_s = 1e-6 * o.GetDouble("device-deadline-us", 10.0, 1e6);
    c.hiro_config = o.GetString("hiro-config");
    c.cache_dir = o.GetString("cache");
    c.script = o.GetString("script");
    c.replay_file = o.GetString("replay");
    c.replay_loop = o.FlagSet("replay-loop");
    if (c.device == "replay" && c.replay_file.empty()) {
      throw handshare::common::OptionError("option --device replay needs --replay FILE");
    }
    c.rate_Hz = o.GetDouble("rate", 100.0, 20000.0);
    c.publish_Hz = o.GetDouble("publish-rate", 1.0, 1000.0);
    c.deadband_weber = o.GetDouble("deadband", 0.0, 0.5);
    c.coupling_passivity = o.GetChoice("coupling-passivity", {"on", "off"}) == "on";
    c.coupling_on_wake = o.GetChoice("coupling", {"woken", "polled"}) == "woken";
    c.trace_file = o.GetString("trace");
    c.dump_dir = o.GetString("dump-deformation");
    c.paced_streams = o.GetChoice("streams", {"paced", "full"}) == "paced";
    c.rejoin_after_s = o.GetDouble("rejoin-after", 0.0, 3600.0);
    return handshare::haptic::HapticNode(c).Run();
  });
}
