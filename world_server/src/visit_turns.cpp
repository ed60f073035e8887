#include "handshare/world_server/visit_turns.hpp"

#include <algorithm>
#include <cstdio>

namespace handshare::server {

std::vector<scene::Message> TurnOverMessages(const std::string& user, std::optional<double> minutes) {
  char length[32] = "";
  if (minutes) std::snprintf(length, sizeof length, "%g", *minutes);
  scene::Message en;
  en.language = "en";
  en.text = minutes ? "Thank you, " + user + ": your " + length + " minutes are over."
                    : "Thank you, " + user + ": your turn is over.";
  en.next_action = "Please take your hand out of the device, then answer the questionnaire on the tablet.";
  scene::Message ja;
  ja.language = "ja";
  ja.text = minutes ? user + "さん、" + length + "分の体験が終わりました。ありがとうございました。"
                    : user + "さん、体験が終わりました。ありがとうございました。";
  ja.next_action = "手を装置から外して、タブレットのアンケートに答えてください。";
  // The ja voice reads kana and ASCII only (common::FirstOutsideKanaReading).
  ja.reading = (minutes ? user + " さん、" + length + " ふんの たいけんが おわりました。ありがとう ございました。"
                        : user + " さん、たいけんが おわりました。ありがとう ございました。") +
               "てを そうちから はずして、タブレットの アンケートに こたえて ください。";
  return {en, ja};
}

namespace {
// Screens, guides and consoles take no turn: a visitor is at a haptic station.
bool IsVisitor(const Member& member) { return member.kind == "haptic"; }
}  // namespace

void VisitTurns::OnMember(MemberChange change, const Member& member, Clock::time_point now) {
  if (change != MemberChange::kJoined) {
    open_.erase(member.member_id);
    return;
  }
  if (!IsVisitor(member)) return;
  open_.try_emplace(member.member_id, Turn{member, now});
}

std::vector<VisitTurns::Ended> VisitTurns::TakeEnded(Clock::time_point now) {
  std::vector<Ended> out;
  if (!enabled()) return out;
  for (auto it = open_.begin(); it != open_.end();) {
    if (now - it->second.start >= length_) {
      out.push_back(Ended{it->second.member, now - it->second.start});
      it = open_.erase(it);
    } else {
      ++it;
    }
  }
  std::sort(out.begin(), out.end(), [](const Ended& a, const Ended& b) { return a.turn > b.turn; });
  return out;
}

std::optional<VisitTurns::Ended> VisitTurns::EndNow(const std::string& user, Clock::time_point now) {
  for (auto it = open_.begin(); it != open_.end(); ++it) {
    if (it->second.member.user != user) continue;
    Ended e{it->second.member, now - it->second.start};
    open_.erase(it);
    return e;
  }
  return std::nullopt;
}

std::vector<VisitTurns::Ended> VisitTurns::Restart(const std::vector<Member>& present, Clock::time_point now) {
  std::vector<Ended> out;
  for (const auto& [id, turn] : open_) out.push_back(Ended{turn.member, now - turn.start});
  std::sort(out.begin(), out.end(), [](const Ended& a, const Ended& b) { return a.turn > b.turn; });
  open_.clear();
  for (const Member& member : present) {
    if (IsVisitor(member)) open_.emplace(member.member_id, Turn{member, now});
  }
  return out;
}

}  // namespace handshare::server
