#include "handshare/world_server/member_registry.hpp"

#include <algorithm>

#include "handshare/dds/name_binding.hpp"

namespace handshare::server {

std::optional<MemberEvent> MemberRegistry::OnInfo(const InstanceKey& key, const InstanceKey& writer,
                                                  const Member& member) {
  lost_.erase(key);  // announced again (by the same writer, or a restarted process's new one)
  const auto [it, inserted] = present_.try_emplace(key, Entry{member, writer});
  if (!inserted) {
    it->second = Entry{member, writer};  // an update of a present member is not a join
    return std::nullopt;
  }
  ++joined_total_;
  return MemberEvent{MemberChange::kJoined, member};
}

std::optional<MemberEvent> MemberRegistry::OnGone(const InstanceKey& key, bool disposed) {
  const auto it = present_.find(key);
  if (it == present_.end()) return std::nullopt;  // unknown or already gone: report once
  MemberEvent event{disposed ? MemberChange::kLeft : MemberChange::kLost, it->second.member};
  present_.erase(it);
  return event;
}

std::vector<MemberEvent> MemberRegistry::OnWriterLost(const InstanceKey& writer) {
  std::vector<MemberEvent> events;
  for (auto it = present_.begin(); it != present_.end();) {
    if (it->second.writer == writer) {
      events.push_back(MemberEvent{MemberChange::kLost, it->second.member});
      lost_.insert_or_assign(it->first, it->second);
      it = present_.erase(it);
    } else {
      ++it;
    }
  }
  return events;
}

std::vector<MemberEvent> MemberRegistry::OnWriterRegained(const InstanceKey& writer) {
  std::vector<MemberEvent> events;
  for (auto it = lost_.begin(); it != lost_.end();) {
    if (it->second.writer == writer && present_.try_emplace(it->first, it->second).second) {
      ++joined_total_;
      events.push_back(MemberEvent{MemberChange::kJoined, it->second.member});
      it = lost_.erase(it);
    } else {
      ++it;
    }
  }
  return events;
}

std::string MemberRegistry::CheckAuthor(const std::string& user, const InstanceKey& writer) const {
  for (const auto& [key, e] : present_) {
    if (e.member.user != user || dds::SameParticipant(e.writer, writer)) continue;
    return dds::AuthorMismatch(user, e.writer, writer);
  }
  return {};
}

std::vector<Member> MemberRegistry::present() const {
  std::vector<Member> out;
  for (const auto& [key, e] : present_) out.push_back(e.member);
  return out;
}

const char* ToString(MemberChange change) {
  switch (change) {
    case MemberChange::kJoined: return "joined";
    case MemberChange::kLeft: return "left";
    case MemberChange::kLost: return "lost";
  }
  return "?";
}

}  // namespace handshare::server
