#include "handshare/controls/control_table.hpp"

#include <cmath>

#include "handshare/controls/visit_answers.hpp"

namespace handshare::controls {

Summary Summarize(const std::vector<double>& values) {
  Summary s;
  s.n = values.size();
  if (s.n == 0) return s;
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / static_cast<double>(s.n);
  if (s.n < 2) return s;
  // Two passes: the sum of squared deviations does not cancel like sum(x^2) - n mean^2.
  double squares = 0.0;
  for (double v : values) squares += (v - s.mean) * (v - s.mean);
  s.sd = std::sqrt(squares / static_cast<double>(s.n - 1));
  return s;
}

bool IsHit(EventKind kind) {
  return kind == EventKind::kPressed || kind == EventKind::kMoved || kind == EventKind::kPageTurned ||
         kind == EventKind::kOpened;
}

void EventTally::Add(EventKind kind, const std::string& user, std::optional<double> error_m) {
  if (IsHit(kind)) {
    ++hits_;
    misses_by_user_.try_emplace(user, 0);
    if (error_m && std::isfinite(*error_m)) errors_.push_back(*error_m);
  } else if (kind == EventKind::kMissed) {
    ++misses_;
    ++misses_by_user_[user];
  } else {
    ++released_;
  }
}

Summary EventTally::misses_per_user() const {
  std::vector<double> per_user;
  for (const auto& [user, n] : misses_by_user_) per_user.push_back(static_cast<double>(n));
  return Summarize(per_user);
}

void KindTable::Add(const std::string& control_id, std::optional<scene::ControlType> kind, EventKind event,
                    const std::string& user, std::optional<double> error_m) {
  // "unknown" sorts after the four kinds' names, which std::map keeps in the paper's order.
  auto& [tally, ids] = by_kind_[kind ? ToString(*kind) : kUnknown];
  tally.Add(event, user, error_m);
  ids.insert(control_id);
}

std::vector<KindTable::Row> KindTable::Rows() const {
  std::vector<Row> out;
  for (const auto& [kind, group] : by_kind_) out.push_back(Row{kind, group.second.size(), group.first});
  return out;
}

}  // namespace handshare::controls
