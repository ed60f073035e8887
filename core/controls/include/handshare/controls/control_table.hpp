#pragma once
/// The paper's Table 4 (hits, misses and errors per kind of control, misses per user) as every
/// place that shows it counts it: `session_report` from a session log, the web console live
/// from the control events it hears. One rule, so the two cannot disagree. Not real-time.
#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "handshare/controls/controls.hpp"

namespace handshare::controls {

/// Sample mean and standard deviation (n - 1 in the denominator, as SPSS reports and as the
/// paper's Table 4 is consistent with). sd is 0 for n < 2; mean is 0 for n = 0.
struct Summary {
  std::size_t n = 0;
  double mean = 0.0;
  double sd = 0.0;
};
Summary Summarize(const std::vector<double>& values);

/// An actuation that counts as a hit: pressed, moved (a lever), a page turned, a book opened.
bool IsHit(EventKind kind);

/// The events of one group (a control, or a kind of control).
class EventTally {
 public:
  /// One event of `user`; `error_m` is how far from the target a hit landed, when known
  /// (motion reports, kMoving, are not events of the table: the caller leaves them out).
  void Add(EventKind kind, const std::string& user, std::optional<double> error_m);

  std::size_t hits() const { return hits_; }
  std::size_t misses() const { return misses_; }
  std::size_t released() const { return released_; }
  /// error_m of the hits that carry a finite one: how far from the target the hits landed.
  Summary error_m() const { return Summarize(errors_); }
  /// Misses per user, over the users who tried (hit or miss): the paper's Table 4 (count =
  /// users, mean and sd of their misses).
  Summary misses_per_user() const;

 private:
  std::size_t hits_ = 0, misses_ = 0, released_ = 0;
  std::vector<double> errors_;
  std::map<std::string, std::size_t> misses_by_user_;  // every user who tried, 0 if never missed
};

/// Table 4 by kind of control: arrow, book, button, lever, and "unknown" for a control whose
/// kind the caller does not know.
class KindTable {
 public:
  static constexpr const char* kUnknown = "unknown";
  void Add(const std::string& control_id, std::optional<scene::ControlType> kind, EventKind event,
           const std::string& user, std::optional<double> error_m);

  struct Row {
    std::string kind;
    std::size_t controls = 0;  ///< control ids of this kind with events
    EventTally tally;
  };
  /// One row per kind with events, in the paper's order (alphabetical), "unknown" last.
  std::vector<Row> Rows() const;
  bool empty() const { return by_kind_.empty(); }

 private:
  std::map<std::string, std::pair<EventTally, std::set<std::string>>> by_kind_;  // tally, control ids
};

}  // namespace handshare::controls
