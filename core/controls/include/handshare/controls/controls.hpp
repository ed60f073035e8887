#pragma once
/// Haptic controls of the encyclopedia (HIRO II chapter, section 1.6, Fig. 11): push buttons,
/// levers, arrows and books that push back on the fingertips like the real ones, and report
/// what the visitor did with them, including misses (Table 4 / Fig. 17 count a control the
/// visitor reached for and did not actuate as an error).
///
/// Real-time: Step() is noexcept and does not allocate, lock, log or throw; construction
/// (MakeControls) allocates. One ControlSet per haptic node, stepped in the haptic thread.
///
/// Fingertips come as one flat array, kFingers per hand (thumb first), several hands:
/// fingertip i belongs to hand i / kFingers. A NaN position marks a fingertip that is
/// not tracked; it gets no force and is ignored.
///
/// Frames (C: the control's frame from its scene entry, position_m + orientation_wxyz):
///   button, arrow: origin at the centre of the top (push) face, z out of the face; the face
///     spans |x| <= size.x/2, |y| <= size.y/2 and moves down (-z) by up to travel_m.
///   lever: hinge axis along x through the origin; the handle (size.x wide, size.y thick,
///     size.z long) points along z at angle 0 and turns towards -y as the angle grows, so it is
///     pushed from its +y side. Angles are limited to [min_angle_rad, max_angle_rad].
///   book: lies closed on its back cover; origin at the centre of the top of the closed book,
///     x across (spine at x = -size.x/2), y along the spine, z up; size.z thick. Opened, the
///     left page lies over -3 size.x/2 <= x <= -size.x/2.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "handshare/common/hand.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::controls {

using common::kFingers;  // fingertips per hand (handshare/common/hand.hpp)
inline constexpr int kMaxHands = 8;
inline constexpr int kMaxFingertips = kFingers * kMaxHands;

enum class EventKind : std::uint8_t {
  kPressed,     ///< button or arrow clicked (went past click_at_m)
  kReleased,    ///< button or arrow came back above release_at_m
  kMoved,       ///< lever settled in a detent (or end stop) other than the last one
  kPageTurned,  ///< book page turned; index = the page now shown
  kMissed,      ///< a hand entered the approach zone and left without actuating the control
  kOpened,      ///< book cover pushed past open_angle_rad: the book is open at page 0
  /// a hand moves the control (not an actuation): value = its position now (Control::position);
  /// index 1 while it moves, 0 once it is left alone and still (its last report)
  kMoving,
};
const char* ToString(EventKind kind) noexcept;

/// One control event: plain, trivially copyable, fixed size (fits a lock-free queue and a DDS
/// @final struct).
///
/// error_m, the position error of the attempt (Table 4 reports the number of misses per
/// control; the distance says how far off the visitor was, for hits and misses alike):
///   kPressed, kReleased: distance in the face plane from the face centre to the fingertip.
///   kMoved: distance from the knob (top of the handle) to the fingertip that last pushed.
///   kOpened: distance from the middle of the cover's free edge to where the finger first
///     touched; kPageTurned: from the centre of the page swiped to where the finger first
///     touched.
///   kMissed: the closest any fingertip of the hand came to that same target point.
///   kMoving: 0 (no attempt; hand and finger -1).
struct ControlEvent {
  std::array<char, 32> control_id{};  ///< NUL-terminated
  scene::ControlType type = scene::ControlType::kButton;
  EventKind kind = EventKind::kPressed;
  std::int32_t index = -1;   ///< lever: detent; book: page (0 = first spread); moving: 1
                             ///< moving, 0 at rest; else -1
  double value = 0.0;        ///< button/arrow: travel [m]; lever: angle [rad]; book: page;
                             ///< missed: closest distance to the target [m]; moving: position
  double error_m = 0.0;      ///< see above
  std::int32_t hand = -1;    ///< hand index (fingertip / kFingers)
  std::int32_t finger = -1;  ///< fingertip index within the hand (0 = thumb)
  std::string_view id() const noexcept { return control_id.data(); }
};

/// Fixed-capacity event list, filled by Step(), emptied by the caller (Clear()). Never
/// allocates; events beyond the capacity are counted in dropped() and lost.
class EventBuffer {
 public:
  static constexpr int kCapacity = 64;
  bool Push(const ControlEvent& e) noexcept {
    if (size_ >= kCapacity) {
      ++dropped_;
      return false;
    }
    events_[static_cast<std::size_t>(size_++)] = e;
    return true;
  }
  void Clear() noexcept { size_ = 0; }
  int size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  long dropped() const noexcept { return dropped_; }
  const ControlEvent& operator[](int i) const noexcept { return events_[static_cast<std::size_t>(i)]; }
  const ControlEvent* begin() const noexcept { return events_.data(); }
  const ControlEvent* end() const noexcept { return events_.data() + size_; }

 private:
  std::array<ControlEvent, kCapacity> events_{};
  int size_ = 0;
  long dropped_ = 0;
};

/// Base of every control: pose, fingertip transform, force clamp and miss detection around a
/// model (the derived class) that computes forces and actuation events in frame C.
class Control {
 public:
  explicit Control(const scene::ControlSpec& spec);
  virtual ~Control() = default;
  Control(const Control&) = delete;
  Control& operator=(const Control&) = delete;

  /// One haptic step.
  /// @param dt_s                time since the last step [s] (> 0).
  /// @param p_WE                fingertip centres in W [m], kFingers per hand; NaN: absent.
  /// @param fingertip_radius_m  radius of the fingertip spheres [m].
  /// @param f_E_W               forces on the fingertips in W [N]; this control's forces are
  ///                            ADDED (same size as p_WE; each finger's share clamped to
  ///                            max_force_N).
  /// @param events              events are appended (PRESSED ... MISSED).
  /// Fingertips beyond kMaxFingertips are ignored.
  void Step(double dt_s, std::span<const Eigen::Vector3d> p_WE, double fingertip_radius_m,
            std::span<Eigen::Vector3d> f_E_W, EventBuffer& events) noexcept;

  const scene::ControlSpec& spec() const noexcept { return spec_; }
  const std::string& id() const noexcept { return spec_.id; }
  scene::ControlType type() const noexcept { return spec_.type; }
  /// Misses counted so far (Table 4's error count for this control).
  long missed_count() const noexcept { return missed_count_; }
  /// The scene action an event of this control triggers, or nullptr.
  const scene::Action* ActionFor(const ControlEvent& e) const noexcept;
  /// On: a hand already at the control at its first step (it was there when the world
  /// appeared) does not actuate it until it has left; the arrow of the next world, at the place
  /// of the arrow just pressed, is then not pressed by the same push. Off by default.
  void SetGuardFirstVisits(bool on) noexcept { guard_first_visits_ = on; }
  /// Puts the control where the session's last actuation left it (the world server's control
  /// state: another user moved it, or this world was rebuilt): a lever into detent `index`, a
  /// book open (`engaged`) at page `index` or shut. Buttons and arrows spring back by
  /// themselves: nothing. Silently ignores an index the control does not have.
  virtual void ApplyState(std::int32_t index, bool engaged) noexcept {
    (void)index;
    (void)engaged;
  }
  /// The same from elsewhere while the haptic loop steps the control (another user moved it):
  /// applied at the start of the next Step() in which no fingertip is in the approach zone, so
  /// a hand at the control is not overridden; a newer request replaces a waiting one.
  void RequestState(std::int32_t index, bool engaged) noexcept { requested_ = {true, index, engaged}; }
  /// Whether a fingertip of any hand is in the control's approach zone.
  bool touched() const noexcept;
  /// Where the control is now, continuously: a button's or arrow's travel [m], a lever's angle
  /// [rad], a book's cover angle [rad] (pi: open).
  virtual double position() const noexcept = 0;

  /// Motion reports (kMoving): while a hand moves the control, its position at most every
  /// kMotionPeriod_s and only when it moved by more than its resolution (a button's travel / 20,
  /// 0.01 rad for a lever, 0.05 rad for a book's cover) since the last report; once no hand is
  /// at it and it is still, one last report at rest. Screens draw it moving with them; the
  /// settled events (PRESSED ... OPENED) say where it ends up.
  static constexpr double kMotionPeriod_s = 0.04;

 protected:
  /// Fingertips in C, valid ones only flagged in `present`.
  struct Fingers {
    std::span<const Eigen::Vector3d> p_CE;
    std::span<const bool> present;
    double radius_m;
  };
  /// Computes forces in C (added into f_E_C, zeroed by the caller) and reports actuation
  /// through Emit().
  virtual void StepModel(double dt_s, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                         EventBuffer& events) noexcept = 0;
  /// Box around the control in C (at its current state): the approach zone is this box grown
  /// by approach_margin_m.
  virtual Eigen::AlignedBox3d Bounds_C() const noexcept = 0;
  /// The point a visitor should touch to actuate the control now, in C (for error_m).
  virtual Eigen::Vector3d Target_C() const noexcept = 0;

  /// Appends an event for fingertip `tip` (flat index) and marks its hand's visit as actuated
  /// (for kPressed, kMoved, kOpened, kPageTurned).
  void Emit(EventBuffer& events, EventKind kind, int tip, double value, double error_m,
            int index = -1) noexcept;

  scene::ControlSpec spec_;

 private:
  bool guard_first_visits_ = false;
  /// Reports the control's motion (kMoving) after a step.
  void ReportMotion(double dt_s, EventBuffer& events) noexcept;
  /// Takes the control's position as already known (no report): at the first step, and after
  /// a state set from elsewhere (ApplyState).
  void SyncMotion() noexcept;
  double motion_resolution_ = 0.0;
  double last_position_ = 0.0;      // at the previous step
  double reported_position_ = 0.0;  // in the last report (or as synced)
  double since_report_s_ = 0.0;
  bool reporting_ = false;          // reports went out since the control was last at rest
  struct Requested {
    bool waiting = false;
    std::int32_t index = -1;
    bool engaged = false;
  } requested_;
  void TrackApproach(const Fingers& fingers, EventBuffer& events) noexcept;

  struct Visit {
    bool inside = false;
    bool actuated = false;
    bool counts = true;  ///< false for a hand already inside when the control appeared
    double closest_m = 0.0;
    int closest_tip = -1;
  };
  Eigen::Isometry3d X_CW_;
  Eigen::Matrix3d R_WC_;
  std::array<Eigen::Vector3d, kMaxFingertips> p_CE_{};
  std::array<bool, kMaxFingertips> present_{};
  std::array<Eigen::Vector3d, kMaxFingertips> f_E_C_{};
  std::array<Visit, kMaxHands> visits_{};
  bool first_step_ = true;
  long missed_count_ = 0;
};

/// Push button (and arrow): a spring along -z of C with a preload, a click at click_at_m where
/// the force drops by click_drop (it stays lower until the button comes back above
/// release_at_m, like a tactile switch), and a stiff bottom stop at travel_m. The cap is
/// massless and follows the deepest fingertip on it.
/// Force on the pushing fingertip (+z of C):
///   F(q) = (preload_N min(1, q / 0.3 mm) + stiffness_N_per_m q) (1 - click_drop if clicked)
///          + stop_stiffness_N_per_m max(0, d - travel_m),   q = min(d, travel_m)
/// with d the fingertip's depth below the top face (d = r - z).
class PushControl final : public Control {
 public:
  explicit PushControl(const scene::ControlSpec& spec);
  double travel_m() const noexcept { return travel_m_; }
  double position() const noexcept override { return travel_m_; }
  bool pressed() const noexcept { return pressed_; }
  /// Spring force at travel q [N] (before the bottom stop) in the current click state.
  double SpringForce_N(double q_m, bool clicked) const noexcept;

 private:
  void StepModel(double dt_s, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                 EventBuffer& events) noexcept override;
  Eigen::AlignedBox3d Bounds_C() const noexcept override;
  Eigen::Vector3d Target_C() const noexcept override { return Eigen::Vector3d::Zero(); }

  double travel_m_ = 0.0;
  bool pressed_ = false;
  int last_tip_ = -1;
};

/// Lever: a handle on a hinge with a rotary detent spring
///   tau(angle) = -detent_torque_N_m sin(2 pi (angle - min_angle_rad) / spacing),
///   spacing = (max - min) / (detents - 1),
/// so every detent (both end stops included) is a stable rest and the torque peaks between
/// them: a push must overcome the peak, then the lever snaps into the next detent. Fingertips
/// are one-sided constraints on the handle (massless, stiff contact): a fingertip on the +y
/// side can only push the angle up, one on the -y side only down; at an end stop the handle
/// does not give and the fingertip meets stop_stiffness_N_per_m. Without contact the handle
/// settles into the nearest detent at up to settle_rate_rad_per_s.
class Lever final : public Control {
 public:
  explicit Lever(const scene::ControlSpec& spec);
  double angle_rad() const noexcept { return angle_rad_; }
  double position() const noexcept override { return angle_rad_; }
  int detent() const noexcept { return detent_; }
  double DetentTorque_N_m(double angle_rad) const noexcept;
  /// Into detent `index` (0 .. detents - 1), without an event (the move was reported elsewhere).
  void ApplyState(std::int32_t index, bool engaged) noexcept override;

 private:
  void StepModel(double dt_s, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                 EventBuffer& events) noexcept override;
  Eigen::AlignedBox3d Bounds_C() const noexcept override;
  Eigen::Vector3d Target_C() const noexcept override;

  double spacing_rad_ = 0.0;
  double angle_rad_ = 0.0;
  int detent_ = 0;
  int last_pusher_ = -1;
};

/// Book: opens when a fingertip pressing on the closed cover drags it towards the spine: the
/// cover turns with the finger (angle = pi * drag / width) and, past open_angle_rad, falls open
/// (kOpened, page 0). On the open book a swipe of swipe_m on the right page towards the spine
/// turns to the next page, a swipe on the left page away from the spine to the previous one
/// (kPageTurned with the page number); one page per touch. The surface pushes back with
/// surface_stiffness_N_per_m, and a dragged cover or page resists with up to page_drag_N.
/// Without a finger the half-lifted cover falls back shut.
class Book final : public Control {
 public:
  explicit Book(const scene::ControlSpec& spec);
  bool open() const noexcept { return open_; }
  int page() const noexcept { return page_; }
  /// Open at page `index` (engaged), or shut; without an event.
  void ApplyState(std::int32_t index, bool engaged) noexcept override;
  double cover_angle_rad() const noexcept { return cover_angle_rad_; }
  double position() const noexcept override { return cover_angle_rad_; }

 private:
  void StepModel(double dt_s, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                 EventBuffer& events) noexcept override;
  Eigen::AlignedBox3d Bounds_C() const noexcept override;
  Eigen::Vector3d Target_C() const noexcept override;

  struct Touch {
    bool active = false;
    bool used = false;  ///< already turned the cover or a page: lift to turn another
    Eigen::Vector2d start_xy = Eigen::Vector2d::Zero();
  };
  std::array<Touch, kMaxFingertips> touches_{};
  bool open_ = false;
  int page_ = 0;
  double cover_angle_rad_ = 0.0;
};

/// All controls of a scene.
class ControlSet {
 public:
  ControlSet() = default;
  explicit ControlSet(std::vector<std::unique_ptr<Control>> controls);

  /// Steps every control. f_E_W is OVERWRITTEN with the sum of the controls' forces, each
  /// finger's total clamped to the largest max_force_N of the set. Events are appended.
  void Step(double dt_s, std::span<const Eigen::Vector3d> p_WE, double fingertip_radius_m,
            std::span<Eigen::Vector3d> f_E_W, EventBuffer& events) noexcept;

  std::size_t size() const noexcept { return controls_.size(); }
  Control& operator[](std::size_t i) noexcept { return *controls_[i]; }
  const Control& operator[](std::size_t i) const noexcept { return *controls_[i]; }
  /// nullptr if there is no control `id`.
  Control* Find(std::string_view id) noexcept;
  /// The scene action an event triggers (looked up by its control id), or nullptr.
  const scene::Action* ActionFor(const ControlEvent& e) const noexcept;
  /// Control::SetGuardFirstVisits for every control of the set.
  void SetGuardFirstVisits(bool on) noexcept;

 private:
  std::vector<std::unique_ptr<Control>> controls_;
  double max_force_N_ = 0.0;
};

/// The scene action an event of the control `spec` takes, or nullptr (none, or an empty one):
///   button, arrow: `action` when pressed;
///   book: `action` when its cover opens, or, without one, its first page's (opening shows
///         page 1); `page_actions[i]` when turned to page i;
///   lever: `detent_actions[i]` when it settles in detent i.
/// Releases and misses take none; neither does an index outside the lists. The pointer is
/// into `spec`.
const scene::Action* ActionOf(const scene::ControlSpec& spec, EventKind kind, std::int32_t index) noexcept;

/// One control from its scene entry (button and arrow -> PushControl, lever, book).
std::unique_ptr<Control> MakeControl(const scene::ControlSpec& spec);

/// The controls of a scene (Scene::controls), in file order. Allocates: call at setup.
ControlSet MakeControls(const scene::Scene& scene);

}  // namespace handshare::controls
