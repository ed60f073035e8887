#include "handshare/graphics/spectator.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <atomic>
#include <functional>
#include <memory>

#include <nlohmann/json.hpp>

#include "handshare/node/rejoin_clock.hpp"
#include "handshare/dds/roster_rejoin.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/name_binding.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/common/clock.hpp"
#include "handshare/dds/loop_traffic.hpp"
#include "handshare/dds/pass_statistics.hpp"
#include "handshare/graphics/desk_control.hpp"
#include "handshare/graphics/desk_feedback.hpp"
#include "handshare/graphics/gamepad_control.hpp"
#include "handshare/render/gamepad.hpp"
#include "handshare/graphics/scene_replica.hpp"
#include "handshare/hiro/hiro_model.hpp"
#include "handshare/render/image.hpp"
#include "handshare/render/offscreen_renderer.hpp"
#include "handshare/render/projection.hpp"
#include "handshare/render/window_renderer.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::graphics {

namespace {

using Clock = std::chrono::steady_clock;

/// The fingertip force a desk's colours reach red at [N]: the haptic device limit a desk's hand
/// renders with (haptic::DeviceCapabilities' default, 3.5 N, HIRO II's).
constexpr double kDeskMaxForce_N = 3.5;

/// A user's hand is drawn while its device state is fresher than this.
constexpr auto kHandTimeout = std::chrono::seconds(2);
// The frame loop's statistics (LoopStatistics): as often as a haptic node's.
constexpr auto kStatisticsPeriod = std::chrono::seconds(1);

struct UserHand {
  msg::DeviceState state;
  Clock::time_point received;
};

// The hand base pose of a device state (identity rotation where the quaternion is unusable).
Eigen::Isometry3d HandPose(const msg::DeviceState& s) { return figure::HandBasePose(s.p_WH_m(), s.q_WH_wxyz()); }

/// Everything the view needs, updated from DDS on the render thread.
class WorldView {
 public:
  WorldView(dds::Participant& p, const std::filesystem::path& assets_dir, const std::string& name,
            const std::string& session, const std::string& language)
      : session_(session),
        joined_(Clock::now()),
        prefix_("[graphics_node " + name + "] "),
        scene_reader_(dds::MakeReader<msg::SceneState>(p, dds::topics::kSceneState)),
        device_reader_(dds::MakeReader<msg::DeviceState>(p, dds::topics::kDeviceState)),
        board_reader_(dds::MakeReader<msg::MessageBoard>(p, dds::topics::kMessageBoard)),
        deformation_reader_(dds::MakeReader<msg::Deformation>(p, dds::topics::kDeformation)),
        object_reader_(dds::MakeReader<msg::ObjectState>(p, dds::topics::kObjectState)),
        member_reader_(dds::NameBinding::MakeMemberReader(p, [this](const std::string& line) { Say(line); })),
        control_reader_(dds::MakeReaderIfGranted<msg::ControlState>(
            p, dds::topics::kControlState, [this](const std::string& line) { Say(line); }, "controls are drawn at rest")),
        world_(assets_dir, std::cerr, "[graphics_node " + name + "] ", language),
        language_(language) {
    // The HIRO II's own hand is drawn from its joint angles with its model; without the model
    // file, a HIRO user's hand is fitted to the fingertips like any other.
    const std::filesystem::path hiro_file = assets_dir / "devices" / "hiro2.json";
    try {
      hiro_ = hiro::HiroModel::Load(hiro_file);
    } catch (const std::exception& e) {
      Say(std::string("HIRO II hands are fitted to their fingertips: ") + e.what());
    }
  }

  void Update() {
    dds::SampleMeta meta;
    msg::SceneState scene;
    while (scene_reader_.TakeNext(scene, meta)) {
      if (meta.valid_data && Accept("scene_state", "participant " + dds::ParticipantOf(meta.writer), dds::CheckSceneState(scene, session_))) {
        if (scene.scene().to_string() != scene_name_) first_seen_.clear();  // poses, fields: per scene
        world_.OnSceneState(scene);
        scene_name_ = scene.scene().to_string();
        scene_revision_ = scene.revision();
        Arrived("scene '" + scene_name_ + "' revision " + std::to_string(scene_revision_));
      }
    }
    // Deformations and object states name objects of a scene: take them only once a scene is
    // known (a late joiner may get their transient-local history before the scene state's),
    // and after this round's scene state, so they apply to the scene they were sent for.
    if (world_.has_scene()) {
      while (deformation_reader_.TakeNext(deformation_, meta)) {
        if (meta.valid_data && Accept("deformation", "participant " + dds::ParticipantOf(meta.writer), dds::CheckDeformation(deformation_, session_))) {
          world_.OnDeformation(deformation_);
          const std::string id = deformation_.object_id().to_string();
          if (world_.deformation(id) != nullptr && first_seen_.insert("deformation " + id).second) {
            Arrived("first deformation of '" + id + "' (revision " + std::to_string(deformation_.revision()) +
                    (deformation_.keyframe() ? ", keyframe)" : ")"));
          }
        }
      }
      msg::ObjectState object;
      while (object_reader_.TakeNext(object, meta)) {
        if (meta.valid_data &&
            Accept("object_state", object.owner().to_string(), dds::CheckObjectState(object, session_))) {
          world_.OnObjectState(object);
          const std::string id = object.object_id().to_string();
          if (world_.pose_received(id) && first_seen_.insert("pose " + id).second) {
            Arrived("first pose of '" + id + "'");
          }
        }
      }
    }
    // A hand in a present user's name from another participant is not drawn (forged).
    names_.Follow(member_reader_);
    msg::DeviceState state;
    while (device_reader_.TakeNext(state, meta)) {
      if (!meta.valid_data) continue;
      std::string bad = dds::CheckDeviceState(state, session_);
      if (bad.empty()) bad = names_.Check(state.user().to_string(), meta.writer);
      if (Accept("device_state", state.user().to_string(), bad)) {
        hands_[state.user().to_string()] = UserHand{state, Clock::now()};
      }
    }
    msg::ControlState control;
    while (control_reader_ && control_reader_.TakeNext(control, meta)) {
      if (meta.valid_data && Accept("control_state", "participant " + dds::ParticipantOf(meta.writer),
                                    dds::CheckControlState(control, session_))) {
        world_.OnControlState(control);
        if (control.moving()) continue;  // a hand moving it: drawn, not logged
        Arrived("control '" + control.control_id().to_string() + "' of '" + control.scene().to_string() +
                "' at index " + std::to_string(control.index()) + (control.engaged() ? ", engaged" : "") +
                (control.user().to_string().empty() ? "" : " (by " + control.user().to_string() + ")"));
      }
    }
    msg::MessageBoard board;
    while (board_reader_.TakeNext(board, meta)) {
      if (meta.valid_data && Accept("message_board", "participant " + dds::ParticipantOf(meta.writer), dds::CheckMessageBoard(board, session_))) {
        // The board comes in every language of the scene: this view shows its own.
        if (board.language().to_string() != language_) continue;
        board_text_ = board.text().to_string();
        next_action_ = board.next_action().to_string();
        board_id_ = board.message_id();
        Arrived("message board #" + std::to_string(board_id_));
      }
    }
    for (auto it = hands_.begin(); it != hands_.end();) {
      it = (Clock::now() - it->second.received > kHandTimeout) ? hands_.erase(it) : std::next(it);
    }
  }

  /// The camera of `user`'s own view at their latest hand pose; `fallback` while they are not
  /// seen (or their device is faulted).
  render::Camera UserCamera(const std::string& user, const UserEye& eye, const render::Camera& fallback) const {
    const auto it = hands_.find(user);
    if (it == hands_.end() || it->second.state.fault()) return fallback;
    return UserEyeCamera(HandPose(it->second.state), eye, fallback);
  }

  /// From now on, `notify` runs on the middleware's thread whenever a device state arrives
  /// (it must only signal; this thread takes the states in Update).
  void OnDeviceState(std::function<void()> notify) { device_reader_.OnDataAvailable(std::move(notify)); }

  /// The user whose hand a frame follows: `user` (a user's view), or, for a spectator (""),
  /// the one whose state is the newest.
  std::string FrameUser(const std::string& user) const {
    if (!user.empty()) return user;
    std::string newest;
    std::uint64_t stamp = 0;
    for (const auto& [name, hand] : hands_) {
      if (hand.state.stamp_ns() > stamp) {
        stamp = hand.state.stamp_ns();
        newest = name;
      }
    }
    return newest;
  }

  /// The stamp of a user's newest device state (0: none).
  std::uint64_t HandStamp(const std::string& user) const {
    const auto it = hands_.find(user);
    return it == hands_.end() ? 0 : it->second.state.stamp_ns();
  }

  /// The hand base a user's hand is drawn at, if one is.
  std::optional<Eigen::Vector3d> HandBase(const std::string& user) const {
    const auto it = hands_.find(user);
    if (it == hands_.end() || it->second.state.fault()) return std::nullopt;
    return HandPose(it->second.state).translation();
  }

  /// The member ids (MemberInfo::member_id) of the members this view has heard.
  std::vector<std::string> HeardMemberIds() const {
    std::vector<std::string> ids;
    for (const std::string& user : names_.users()) ids.push_back(session_ + "/" + user);
    return ids;
  }

  bool has_scene() const { return world_.has_scene(); }
  const std::string& scene_name() const { return scene_name_; }
  std::uint32_t scene_revision() const { return scene_revision_; }
  const std::map<std::string, UserHand>& hands() const { return hands_; }
  const SceneReplica& world() const { return world_; }
  const dds::DroppedSamples& dropped() const { return dropped_; }
  /// A user's device-state stream that stalled for a deadline period (100 ms): counted, and the
  /// hand is dropped from the view when it stays silent for kHandTimeout.
  std::uint64_t device_deadlines_missed() const { return device_reader_.deadlines_missed(); }

  /// The scene, board and poses shown, as JSON (SpectatorConfig::state_out).
  void WriteStateJson(const std::filesystem::path& file) const {
    nlohmann::ordered_json objects = nlohmann::ordered_json::object();
    for (const std::string& id : world_.object_ids()) {
      const Eigen::Isometry3d X = *world_.X_WO(id);
      const Eigen::Quaterniond q(X.linear());
      objects[id] = {{"p_WO_m", {X.translation().x(), X.translation().y(), X.translation().z()}},
                     {"q_WO_wxyz", {q.w(), q.x(), q.y(), q.z()}},
                     {"from", world_.pose_received(id) ? "object_state" : "scene_state"}};
    }
    nlohmann::ordered_json controls = nlohmann::ordered_json::object();
    for (const std::string& id : world_.object_ids()) {
      if (const auto state = world_.control_state(id)) controls[id] = {{"index", state->first}, {"engaged", state->second}};
    }
    const nlohmann::ordered_json out = {{"scene", scene_name_},
                                        {"revision", scene_revision_},
                                        {"board", {{"message_id", board_id_}, {"language", language_}, {"text", board_text_}, {"next_action", next_action_}}},
                                        {"objects", std::move(objects)},
                                        {"controls", std::move(controls)}};
    std::filesystem::path tmp = file;
    tmp += ".tmp";
    {
      std::ofstream stream(tmp);
      stream << out.dump(2) << "\n";  // doubles round-trip exactly
      if (!stream) throw std::runtime_error("cannot write state file " + tmp.string());
    }
    std::error_code ec;
    std::filesystem::rename(tmp, file, ec);
    if (ec) throw std::runtime_error("cannot write state file " + file.string() + ": " + ec.message());
  }

  /// The frame's content. desk_user: the user whose hand a desk drives here ("" none): their
  /// fingertips show what they feel (desk_feedback.hpp) and the overlay says it, after
  /// `desk_help` (the key mapping, "" hidden).
  render::SceneView Build(const std::string& desk_user = "", const std::string& desk_help = "") const {
    render::SceneView view;
    view.caption = board_text_.empty() || next_action_.empty() ? board_text_ : board_text_ + "\n" + next_action_;
    world_.AddObjects(view);
    for (const auto& [user, hand] : hands_) {
      if (hand.state.fault()) continue;  // a faulted device has no trustworthy pose
      // The hand itself under the fingertips, by the figure's rule (figure::DrawnHand, which
      // the web console's view draws too): a HIRO II's from its joint angles, a pen or a
      // gripper for fewer fingers, any other fitted to the device's hand base and fingertips.
      const unsigned present = ~static_cast<unsigned>(hand.state.absent_fingers()) & 0x1Fu;
      figure::DeviceHand drawn;
      drawn.p_WH_m = hand.state.p_WH_m();
      drawn.q_WH_wxyz = hand.state.q_WH_wxyz();
      for (int i = 0; i < kFingers; ++i) drawn.p_WE[i] = Eigen::Vector3d(hand.state.p_WE_m()[i].data());
      drawn.absent_fingers = hand.state.absent_fingers();
      drawn.fingertip_radius_m = hand.state.fingertip_radius_m();
      drawn.q_hand_rad = hand.state.q_hand_rad();
      drawn.hiro = names_.DeviceOf(user) == "hiro";
      AddHandParts(figure::DrawnHand(drawn, hiro_ ? &*hiro_ : nullptr), view);
      if (user == desk_user) {
        std::array<Eigen::Vector3d, kFingers> tips, forces;
        for (int i = 0; i < kFingers; ++i) {
          tips[i] = Eigen::Vector3d(hand.state.p_WE_m()[i].data());
          forces[i] = Eigen::Vector3d(hand.state.f_E_W_N()[i].data());
        }
        AddForceFeedback(tips, forces, hand.state.fingertip_radius_m(), kDeskMaxForce_N, view);
        continue;
      }
      for (int i = 0; i < 5; ++i) {
        if (((present >> i) & 1u) == 0) continue;  // a finger the device does not have
        const auto& p = hand.state.p_WE_m()[i];
        view.markers.push_back(render::Sphere{
            Eigen::Vector3d(p[0], p[1], p[2]), hand.state.fingertip_radius_m(),
            render::Rgb{kFingertipRgb[i][0], kFingertipRgb[i][1], kFingertipRgb[i][2]}});
      }
    }
    if (!desk_user.empty()) view.overlay = DeskOverlay(desk_user, desk_help);
    view.grid.half_size_m = 0.4;
    view.grid.spacing_m = 0.05;
    return view;
  }

  /// The rumble for what `user`'s hand feels now (none for a hand not here or faulted).
  GamepadRumble Rumble(const std::string& user, const GamepadControl& control) const {
    const auto it = hands_.find(user);
    if (it == hands_.end() || it->second.state.fault()) return {};
    std::array<Eigen::Vector3d, kFingers> forces;
    double largest_N = 0.0;
    for (int i = 0; i < kFingers; ++i) {
      forces[i] = Eigen::Vector3d(it->second.state.f_E_W_N()[i].data());
      largest_N = std::max(largest_N, forces[i].norm());
    }
    return control.RumbleFor(HeldWeight_N(forces), largest_N);
  }

 private:
  // The desk's overlay: the key mapping, then what the hand feels or why there is none.
  std::string DeskOverlay(const std::string& user, const std::string& help) const {
    std::string text = help.empty() ? std::string() : help + "\n";
    const auto it = hands_.find(user);
    if (it == hands_.end()) return text + "waiting for your hand: haptic_node --device desk --user " + user;
    if (it->second.state.fault()) return text + "your hand is released (the window has no focus, or no input)";
    std::array<Eigen::Vector3d, kFingers> forces;
    for (int i = 0; i < kFingers; ++i) forces[i] = Eigen::Vector3d(it->second.state.f_E_W_N()[i].data());
    return text + ForceReadout(forces);
  }

  // When each piece of the shared state first arrived, counted from joining (this view's
  // readers exist): the late joiner's figures (docs/network.md).
  void Arrived(const std::string& what) {
    const double t_s = std::chrono::duration<double>(Clock::now() - joined_).count();
    std::printf("%s%s received %.3f s after joining\n", prefix_.c_str(), what.c_str(), t_s);
    std::fflush(stdout);
  }

  // True when `reason` is empty; else the sample is dropped, counted and (rate-limited) named.
  bool Accept(std::string_view topic, std::string_view sender, const std::string& reason) {
    return dropped_.Accept(topic, sender, reason, [this](const std::string& line) { Say(line); });
  }
  void Say(const std::string& line) const { std::fprintf(stderr, "%s%s\n", prefix_.c_str(), line.c_str()); }
  std::string session_;
  Clock::time_point joined_;
  std::string prefix_;
  std::set<std::string> first_seen_;  // "deformation ID", "pose ID" of this scene already reported
  std::uint32_t board_id_ = 0;
  dds::DroppedSamples dropped_;
  std::string scene_name_;
  std::uint32_t scene_revision_ = 0;
  dds::Reader<msg::SceneState> scene_reader_;
  dds::Reader<msg::DeviceState> device_reader_;
  dds::Reader<msg::MessageBoard> board_reader_;
  dds::Reader<msg::Deformation> deformation_reader_;
  dds::Reader<msg::ObjectState> object_reader_;
  dds::Reader<msg::MemberInfo> member_reader_;
  dds::Reader<msg::ControlState> control_reader_;  // empty: a keystore without the grant
  dds::NameBinding names_;  // present users and the participants that announced them
  msg::Deformation deformation_;  // reused: a sample holds up to 16k values
  SceneReplica world_;
  std::map<std::string, UserHand> hands_;
  std::string language_;     // the board's language shown: en or ja
  std::optional<hiro::HiroModel> hiro_;  // the HIRO II's model, for its users' hands
  std::string board_text_;   // the board shown: its text and what to do next
  std::string next_action_;
};

/// The desk's writer. A keystore (--security) grants no role the desk's topic yet: say so.
dds::Writer<msg::DeskInput> MakeDeskWriter(dds::Participant& participant) {
  try {
    return dds::MakeWriter<msg::DeskInput>(participant, dds::topics::kDeskInput);
  } catch (const dds::DdsError& e) {
    throw std::runtime_error(std::string("--input desk: cannot write ") + dds::topics::kDeskInput.name + " (" + e.what() +
                             "); under --security no keystore role grants it yet (docs/devices.md)");
  }
}

/// Everything of a spectator that lives on DDS: its participant, what it reads and its member
/// announcement. A rejoin makes a new one.
struct SpectatorLink {
  /// fps: the frame rate, announced so that haptic nodes send device states no faster.
  SpectatorLink(const common::SessionOptions& where, const std::filesystem::path& assets_dir, const std::string& name,
                double fps, const std::string& language, bool desk, bool draw_on_state)
      : participant(where, "graphics_node/" + name),  // the role picks its identity
        world(participant, assets_dir, name, where.session, language),
        member(participant, name, msg::NODE_GRAPHICS, "", fps),
        roster(dds::MakeReaderIfGranted<msg::SessionRoster>(
            participant, dds::topics::kSessionRoster,
            [&name](const std::string& line) { std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), line.c_str()); },
            "no rejoin when a member stays unheard")),
        desk_writer(desk ? MakeDeskWriter(participant) : dds::Writer<msg::DeskInput>{}),
        stats_writer(dds::MakeWriterIfGranted<msg::LoopStatistics>(
            participant, dds::topics::kLoopStatistics,
            [&name](const std::string& line) { std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), line.c_str()); },
            "the operator's page shows no frame statistics of this screen")),
        stats_traffic(participant) {
    stats.node("graphics_node/" + name);
    stats.session(where.session);
    // A window draws a hand as soon as its new state is here, not when the next frame is due:
    // the reader's listener wakes the window's wait.
    if (draw_on_state) {
      world.OnDeviceState([arrived = device_arrived] {
        arrived->store(true);
        render::WindowRenderer::Wake();
      });
    }
  }
  dds::Participant participant;
  // The readers first: the server re-sends body poses (best-effort) when it sees the member
  // join, and a reader created after the announcement could miss them.
  WorldView world;
  dds::MemberAnnouncement member;
  dds::Reader<msg::SessionRoster> roster;  // the world server's members: to rejoin if one stays unheard
  dds::Writer<msg::DeskInput> desk_writer;  // --input desk: the person's input, to their haptic node
  dds::Writer<msg::LoopStatistics> stats_writer;  // the frame loop's, once a second; empty: not granted
  dds::LoopTraffic stats_traffic;
  msg::LoopStatistics stats;

  /// Once a second: the frames' statistics, with this participant's traffic and the samples
  /// the world's checks refused. The frames' period restarts whether or not a reader listens.
  void PublishStatistics(dds::PassStatistics& frames, Clock::time_point now) {
    frames.Fill(stats, now);
    stats.samples_dropped(world.dropped().total());
    stats_traffic.Fill(stats, now);
    if (stats_writer && stats_writer.matched_readers() > 0) stats_writer.Write(stats);
  }
  /// A window: a device state arrived since the view last took them (set by the listener).
  std::shared_ptr<std::atomic<bool>> device_arrived = std::make_shared<std::atomic<bool>>(false);
};

// One line on what the shared world received, for the node's log.
void PrintWorldSummary(const std::string& name, const SceneReplica& world, const dds::DroppedSamples& dropped,
                       std::uint64_t device_deadlines_missed) {
  const SceneReplicaStats& s = world.stats();
  const DeformationStats d = world.deformation_stats();
  const auto n = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::printf("[graphics_node %s] deformation: %llu samples (%llu applied, %llu keyframes, %llu ids "
              "out of range, %llu non-finite, %llu malformed, %llu for unknown objects, %llu without "
              "mesh, %llu with another node count); object states: %llu applied, %llu unknown, %llu "
              "non-finite; mesh errors: %llu; device-state deadlines missed: %llu; samples dropped: %s\n",
              name.c_str(), n(s.deformation_samples), n(d.samples), n(d.keyframes),
              n(d.ids_out_of_range), n(d.nonfinite), n(d.malformed), n(s.deformation_unknown_object),
              n(s.deformation_without_mesh), n(s.deformation_count_mismatch), n(s.object_states),
              n(s.object_states_unknown), n(s.object_states_nonfinite), n(s.mesh_errors),
              n(device_deadlines_missed), dropped.Summary().c_str());
  std::fflush(stdout);
}


/// The desk's input as DeskInput samples, with a line in the log when the hand goes live, the
/// window loses or regains focus, and at the end.
class DeskSender {
 public:
  DeskSender(std::string name, const std::string& user, const std::string& session, bool gamepad)
      : name_(std::move(name)), gamepad_(gamepad) {
    msg_.user(user);
    msg_.session(session);
  }
  void Send(const HandTarget& desk, dds::Writer<msg::DeskInput>& writer) {
    const Eigen::Vector3d& p = desk.p_WH;
    const Eigen::Quaterniond& q = desk.q_WH;
    msg_.stamp_ns(common::SteadyNowNs());
    msg_.seq(msg_.seq() + 1);
    msg_.p_WH_m({p.x(), p.y(), p.z()});
    msg_.q_WH_wxyz({q.w(), q.x(), q.y(), q.z()});
    for (int i = 0; i < kFingers; ++i) msg_.closure()[i] = desk.closure[i];
    msg_.focused(desk.focused);
    writer.Write(msg_);
    if (sent_ == 0 || desk.focused != msg_focused_) {
      std::printf("[graphics_node %s] desk: %s, hand target (%.3f, %.3f, %.3f) m\n", name_.c_str(),
                  desk.focused ? (gamepad_ ? "the gamepad is connected: input goes to the hand" : "the window has focus: input goes to the hand")
                               : (gamepad_ ? "the gamepad is unplugged: the hand is released" : "the window has no focus: the hand is released"),
                  p.x(), p.y(), p.z());
      std::fflush(stdout);
    }
    msg_focused_ = desk.focused;
    ++sent_;
  }
  // The window closes: the hand is let go at once, not after the haptic node's timeout.
  void Release(dds::Writer<msg::DeskInput>& writer) {
    if (sent_ == 0) return;
    msg_.focused(false);
    msg_.stamp_ns(common::SteadyNowNs());
    msg_.seq(msg_.seq() + 1);
    writer.Write(msg_);
    std::printf("[graphics_node %s] desk: %llu inputs sent; the hand is released\n", name_.c_str(),
                static_cast<unsigned long long>(sent_));
    std::fflush(stdout);
  }

 private:
  std::string name_;
  bool gamepad_;  // the input is a gamepad's, not the window's mouse and keyboard
  msg::DeskInput msg_;
  std::uint64_t sent_ = 0;
  bool msg_focused_ = false;
};

render::StereoMode ToRender(StereoOutput s) {
  switch (s) {
    case StereoOutput::kSideBySide: return render::StereoMode::kSideBySide;
    case StereoOutput::kAnaglyph: return render::StereoMode::kAnaglyph;
    case StereoOutput::kMono: break;
  }
  return render::StereoMode::kMono;
}

// The camera of a headless run, so anyone can project world points onto the frames.
void WriteCameraJson(const std::filesystem::path& file, const render::Camera& c, StereoOutput stereo) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  out << std::setprecision(17) << "{\n"
      << "  \"convention\": \"OpenGL gluLookAt + gluPerspective, row 0 at the top\",\n"
      << "  \"eye_W_m\": [" << c.eye_W.x() << ", " << c.eye_W.y() << ", " << c.eye_W.z() << "],\n"
      << "  \"target_W_m\": [" << c.target_W.x() << ", " << c.target_W.y() << ", " << c.target_W.z() << "],\n"
      << "  \"up_W\": [" << c.up_W.x() << ", " << c.up_W.y() << ", " << c.up_W.z() << "],\n"
      << "  \"fov_y_rad\": " << c.fov_y_rad << ",\n"
      << "  \"width_px\": " << c.width_px << ",\n  \"height_px\": " << c.height_px << ",\n"
      << "  \"stereo\": \"" << (stereo == StereoOutput::kMono ? "mono" : stereo == StereoOutput::kSideBySide ? "side_by_side" : "anaglyph")
      << "\"\n}\n";
}

}  // namespace

render::Camera SpectatorCamera(int width, int height) {
  render::Camera c;
  c.eye_W = Eigen::Vector3d(0.0, -0.55, 0.45);
  c.target_W = Eigen::Vector3d(0.0, 0.05, 0.05);
  c.up_W = Eigen::Vector3d(0.0, 0.0, 1.0);
  c.fov_y_rad = 0.8;
  c.width_px = width;
  c.height_px = height;
  return c;
}

std::filesystem::path DefaultAssetsDir() { return scene::DefaultSceneDir().parent_path(); }

Spectator::Spectator(SpectatorConfig config) : config_(std::move(config)) {}

int Spectator::Run() {
  const std::string name = config_.name.empty() ? "graphics-" + std::to_string(getpid()) : config_.name;
  const render::Camera camera = SpectatorCamera(config_.width_px, config_.height_px);
  render::ValidateCamera(camera);

  // Bad paths fail here, before any DDS entity or frame exists.
  const std::filesystem::path assets_dir = config_.assets_dir.empty() ? DefaultAssetsDir() : config_.assets_dir;
  if (!std::filesystem::is_directory(assets_dir)) {
    throw std::runtime_error("assets folder " + assets_dir.string() + " does not exist (option --assets)");
  }
  for (const auto& [file, option] : {std::pair{config_.deformation_out, "--deformation-out"},
                                     std::pair{config_.state_out, "--state-out"},
                                     std::pair{config_.frame_log, "--frame-log"}}) {
    if (file.empty()) continue;
    const std::filesystem::path folder = std::filesystem::absolute(file).parent_path();
    if (!std::filesystem::is_directory(folder)) {
      throw std::runtime_error("folder " + folder.string() + " of " + option + " does not exist");
    }
  }

  std::filesystem::path out_dir;
  std::ofstream index;
  std::ofstream times;
  if (config_.headless) {
    out_dir = config_.out_dir;
    std::filesystem::create_directories(out_dir);
    WriteCameraJson(out_dir / "camera.json", camera, config_.stereo);
    // frames.csv: which hands each frame shows and where their fingertips were drawn.
    index.open(out_dir / "frames.csv");
    if (!index) throw std::runtime_error("cannot write " + (out_dir / "frames.csv").string());
    index << "frame,file,user,finger,x_m,y_m,z_m,radius_m\n" << std::setprecision(9);
    // frame_times.csv: what each frame shows by the senders' own stamps (the scene state's
    // revision, each hand's device-state stamp_ns, each moving object's object-state stamp_ns,
    // each deformed mesh's deformation revision),
    // which a replay (session_play) carries unchanged: frames of a live session and of its
    // replay are matched on them.
    times.open(out_dir / "frame_times.csv");
    if (!times) throw std::runtime_error("cannot write " + (out_dir / "frame_times.csv").string());
    times << "frame,file,scene,revision,hands,objects,deformations\n";
  }

  // The renderer before joining: OpenGL's start-up (3.8 s once on a loaded machine) would
  // otherwise hold up the first look at what a late joiner is sent.
  std::optional<render::OffscreenRenderer> offscreen;
  std::optional<render::WindowRenderer> window_renderer;
  if (config_.headless) {
    offscreen.emplace();
  } else {
    render::WindowRenderer::Options options;
    options.title = "handshare - " + config_.where.session;
    if (config_.desk_input) options.title += " - " + config_.view_user + " at the desk";
    options.width_px = config_.width_px;
    options.height_px = config_.height_px;
    options.stereo = ToRender(config_.stereo);
    options.fullscreen = config_.fullscreen;
    window_renderer.emplace(options);
  }

  const auto open_link = [&] {
    return std::make_unique<SpectatorLink>(config_.where, assets_dir, name, config_.fps, config_.language,
                                           config_.desk_input, !config_.headless && config_.frames_follow_states);
  };
  auto link = open_link();
  node::RejoinClock rejoin(config_.rejoin_after);
  // A member the world server has (its roster) that this view never hears, a user's hand
  // above all, is a secured handshake between the two that never finished (Fast DDS 2.9,
  // docs/security.md): a new participant starts it again, as the recorder does.
  dds::RosterRejoin roster_rejoin(config_.rejoin_after, config_.where.session);
  const std::string own_id = config_.where.session + "/" + name;
  const auto rejoin_if_unheard = [&] {
    if (rejoin.Due(link->world.has_scene())) {
      std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), rejoin.Message("scene").c_str());
      const std::string joined = rejoin.Swap(link, open_link);
      std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), joined.c_str());
      roster_rejoin.Restart(Clock::now());
      return;
    }
    roster_rejoin.Take(link->roster);
    std::vector<std::string> heard = link->world.HeardMemberIds();
    heard.push_back(own_id);
    const std::string why = roster_rejoin.Due(heard, Clock::now());
    if (why.empty()) return;
    std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), why.c_str());
    Clock::time_point opened;
    const std::string joined = node::RunRejoin(
        roster_rejoin.rejoins(), Clock::now(), [&] { link.reset(); }, [&] { link = open_link(); }, opened);
    std::fprintf(stderr, "[graphics_node %s] %s\n", name.c_str(), joined.c_str());
    roster_rejoin.Restart(opened);
  };
  // When the frames are written or the window closes: what the spectator received, for a
  // comparison with an oracle.
  const auto finish = [&] {
    WorldView& world = link->world;
    world.Update();  // what arrived since the last frame counts too (a stop between frames)
    PrintWorldSummary(name, world.world(), world.dropped(), world.device_deadlines_missed());
    if (rejoin.rejoins() + roster_rejoin.rejoins() > 0) {
      std::printf("[graphics_node %s] rejoined the session %d time(s)\n", name.c_str(),
                  rejoin.rejoins() + roster_rejoin.rejoins());
    }
    std::printf("[graphics_node %s] %s\n", name.c_str(), link->participant.TrafficSummary().c_str());
    std::fflush(stdout);
    if (!config_.deformation_out.empty()) world.world().WriteDeformationJson(config_.deformation_out);
    if (!config_.state_out.empty()) world.WriteStateJson(config_.state_out);
  };

  const auto start = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.fps));

  if (config_.headless) {
    render::OffscreenRenderer& renderer = *offscreen;
    // Late joiner: the scene arrives transient-local within discovery time; do not draw an
    // empty world unless it never comes.
    while (!link->world.has_scene() && Clock::now() - start < config_.wait_for_scene && !common::ShutdownRequested()) {
      link->world.Update();
      rejoin_if_unheard();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!link->world.has_scene()) std::fprintf(stderr, "[graphics_node %s] no scene state received; drawing hands only\n", name.c_str());
    auto next = Clock::now();
    dds::PassStatistics frame_stats(period, next);
    auto next_stats = next + kStatisticsPeriod;
    int written = 0;
    for (; written < config_.frames && !common::ShutdownRequested(); ++written) {
      const auto due = next;
      const auto began = Clock::now();
      rejoin_if_unheard();
      WorldView& world = link->world;
      world.Update();
      const render::Camera frame_camera =
          config_.view_user.empty() ? camera : world.UserCamera(config_.view_user, config_.eye, camera);
      const render::ImageRgb8 image = renderer.Render(world.Build(), frame_camera, ToRender(config_.stereo));
      char file[32];
      std::snprintf(file, sizeof(file), "frame_%05d.png", written);
      render::WritePng(out_dir / file, image);
      for (const auto& [user, hand] : world.hands()) {
        if (hand.state.fault()) continue;
        for (int i = 0; i < 5; ++i) {
          if ((hand.state.absent_fingers() >> i) & 1u) continue;  // not drawn: the device has no such finger
          const auto& p = hand.state.p_WE_m()[i];
          index << written << "," << file << "," << user << "," << i << "," << p[0] << "," << p[1]
                << "," << p[2] << "," << hand.state.fingertip_radius_m() << "\n";
        }
      }
      times << written << "," << file << "," << world.scene_name() << "," << world.scene_revision() << ",";
      const char* sep = "";
      for (const auto& [user, hand] : world.hands()) {
        times << sep << user << "@" << hand.state.stamp_ns();
        sep = ";";
      }
      // Flushed with each frame: a test reads what the frames show while they are written.
      times << "," << world.world().pose_stamps() << "," << world.world().field_revisions() << "\n" << std::flush;
      const auto ended = Clock::now();
      frame_stats.Record(due, began, ended);
      if (ended >= next_stats) {
        link->PublishStatistics(frame_stats, ended);
        next_stats = ended + kStatisticsPeriod;
      }
      next += period;
      std::this_thread::sleep_until(next);
    }
    std::printf("[graphics_node %s] wrote %d frames to %s\n", name.c_str(), written, out_dir.c_str());
    std::fflush(stdout);
    finish();
    return 0;
  }

  render::WindowRenderer& window = *window_renderer;
  std::ofstream frame_log;
  if (!config_.frame_log.empty()) {
    frame_log.open(config_.frame_log);
    if (!frame_log) throw std::runtime_error("cannot write " + config_.frame_log.string() + " (option --frame-log)");
    frame_log << "frame,t_ns,hand_x_m,hand_y_m,hand_z_m,anchor_x_px,anchor_y_px,hand_stamp_ns,draw_ms\n" << std::setprecision(9);
  }
  std::uint64_t frames_shown = 0;
  auto next = Clock::now();
  dds::PassStatistics frame_stats(period, next);
  auto next_stats = next + kStatisticsPeriod;
  DeskControl desk;
  GamepadControl gamepad;
  std::optional<render::Gamepad> pad;
  if (config_.gamepad_input) pad.emplace();
  DeskSender desk_sender(name, config_.view_user, config_.where.session, config_.gamepad_input);
  auto last_frame = Clock::now();
  while (!window.ShouldClose() && !common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    rejoin_if_unheard();
    link->device_arrived->store(false);  // before the take: a state arriving during it wakes again
    link->world.Update();
    const std::string desk_user = config_.desk_input ? config_.view_user : std::string();
    const std::string help = pad ? GamepadControl::HelpText() : desk.help_shown() ? DeskControl::HelpText() : std::string();
    const render::Camera frame_camera =
        config_.view_user.empty() ? camera : link->world.UserCamera(config_.view_user, config_.eye, camera);
    // What the person did, to their haptic node: every frame, so that a quiet desk is noticed
    // there, and as soon as it happens, between frames and while the driver draws one (the
    // mouse and keys; a gamepad is read at the frame rate).
    const auto send_input = [&] {
      const auto now = Clock::now();
      const double dt_s = std::chrono::duration<double>(now - last_frame).count();
      last_frame = now;
      if (pad) {
        (void)window.TakeInput();  // the gamepad drives the hand, not the window's mouse and keys
        gamepad.Apply(pad->Poll(), dt_s);
        desk_sender.Send(gamepad.target(), link->desk_writer);
        // What the hand feels, as rumble: the held weight and the largest fingertip force.
        const GamepadRumble r = link->world.Rumble(config_.view_user, gamepad);
        pad->Rumble(r.low, r.high, 250);
      } else {
        desk.Apply(window.TakeInput(), dt_s);
        desk_sender.Send(desk.target(), link->desk_writer);
      }
    };
    const auto input_while_drawing = [&](double wait_s) {
      if (window.WaitForInput(wait_s)) send_input();
    };
    const auto frame_due = next;
    const auto frame_start = Clock::now();
    window.Render(link->world.Build(desk_user, help), frame_camera,
                  config_.desk_input && !pad ? std::function<void(double)>(input_while_drawing) : nullptr);
    if (frame_log.is_open()) {
      frame_log << frames_shown << "," << common::SteadyNowNs() << ",";
      const std::string frame_user = link->world.FrameUser(config_.view_user);
      if (const auto p = link->world.HandBase(frame_user)) {
        frame_log << p->x() << "," << p->y() << "," << p->z() << ",";
      } else {
        frame_log << ",,,";
      }
      const Eigen::Vector3d anchor = render::ProjectToImage(frame_camera, Eigen::Vector3d::Zero());
      frame_log << anchor.x() << "," << anchor.y() << "," << link->world.HandStamp(frame_user) << ","
                << std::chrono::duration<double, std::milli>(Clock::now() - frame_start).count() << "\n";
    }
    ++frames_shown;
    const auto shown = Clock::now();
    frame_stats.Record(frame_due, frame_start, shown);
    if (shown >= next_stats) {
      link->PublishStatistics(frame_stats, shown);
      next_stats = shown + kStatisticsPeriod;
    }
    if (config_.desk_input) send_input();
    next += period;
    // Until the next frame is due: the person's input goes out as it arrives, and a new state of
    // a hand (a user's view: their own; a spectator: anyone's) is drawn at once, from half a
    // frame period after the last frame began: at most twice the frame rate however fast states
    // come (a haptic node sends them no faster than the fastest view draws). The frames follow
    // the hands' states, not a clock of their own (docs/devices.md, "Motion to photon").
    const std::string followed = config_.view_user;  // "": any hand
    const auto newest_stamp = [&] {
      return followed.empty() ? link->world.HandStamp(link->world.FrameUser("")) : link->world.HandStamp(followed);
    };
    const std::uint64_t drawn = newest_stamp();
    const auto earliest = frame_start + period / 2;
    for (auto now = Clock::now(); now < next; now = Clock::now()) {
      const auto until = link->device_arrived->load() ? std::min(next, std::max(now, earliest)) : next;
      if (window.WaitForInput(std::chrono::duration<double>(until - now).count()) && config_.desk_input && !pad) {
        send_input();
      }
      if (!link->device_arrived->load() || Clock::now() < earliest) continue;
      link->device_arrived->store(false);
      link->world.Update();
      if (newest_stamp() != drawn) {
        next = Clock::now();  // this frame now; the one after a period later
        break;
      }
    }
  }
  if (config_.desk_input) desk_sender.Release(link->desk_writer);
  finish();
  return 0;
}

}  // namespace handshare::graphics
