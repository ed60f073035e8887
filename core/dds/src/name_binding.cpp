#include "handshare/dds/name_binding.hpp"

#include <algorithm>

namespace handshare::dds {

namespace {
constexpr std::size_t kPrefixBytes = 12;  // a GUID's participant prefix; the rest is the entity
}  // namespace

bool SameParticipant(const Guid& a, const Guid& b) {
  return std::equal(a.begin(), a.begin() + kPrefixBytes, b.begin());
}

std::string ParticipantOf(const Guid& endpoint) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < kPrefixBytes; ++i) {
    out += kHex[endpoint[i] >> 4];
    out += kHex[endpoint[i] & 0xf];
  }
  return out;
}

std::string AuthorMismatch(const std::string& user, const Guid& announced, const Guid& writer) {
  return "user '" + user + "' joined from participant " + ParticipantOf(announced) +
         ", this sample came from participant " + ParticipantOf(writer);
}

void NameBinding::OnMember(const Guid& instance, const std::string& user, const Guid& writer, msg::NodeKind kind,
                           double view_Hz, const std::string& device) {
  members_[instance] = Member{user, writer, kind, view_Hz, device};
}

std::vector<std::string> NameBinding::users() const {
  std::vector<std::string> out;
  for (const auto& [instance, m] : members_) {
    if (std::find(out.begin(), out.end(), m.user) == out.end()) out.push_back(m.user);
  }
  return out;
}

std::string NameBinding::DeviceOf(const std::string& user) const {
  for (const auto& [instance, m] : members_) {
    if (m.user == user && m.kind == msg::NODE_HAPTIC) return m.device;
  }
  return "";
}

Viewers NameBinding::viewers() const {
  Viewers v;
  for (const auto& [instance, m] : members_) {
    if (m.kind != msg::NODE_GRAPHICS) continue;
    ++v.count;
    v.fastest_Hz = std::max(v.fastest_Hz, m.view_Hz);
  }
  return v;
}

void NameBinding::OnMemberGone(const Guid& instance) { members_.erase(instance); }

void NameBinding::OnWriterLost(const Guid& writer) {
  std::erase_if(members_, [&](const auto& m) { return m.second.writer == writer; });
}

std::string NameBinding::Check(const std::string& user, const Guid& writer) const {
  for (const auto& [instance, m] : members_) {
    if (m.user == user && !SameParticipant(m.writer, writer)) return AuthorMismatch(user, m.writer, writer);
  }
  return {};
}

Reader<msg::MemberInfo> NameBinding::MakeMemberReader(Participant& participant,
                                                           const std::function<void(const std::string&)>& say) {
  return MakeReaderIfGranted<msg::MemberInfo>(participant, topics::kMemberInfo, say,
                                              "names are not bound to their participants");
}

void NameBinding::Follow(Reader<msg::MemberInfo>& reader) {
  if (!reader) return;
  msg::MemberInfo info;
  SampleMeta meta;
  while (reader.TakeNext(info, meta)) {
    if (meta.valid_data && meta.instance_state == InstanceState::kAlive && !info.leaving()) {
      OnMember(meta.instance, info.user().to_string(), meta.writer, info.kind(), info.view_Hz(), info.device().to_string());
    } else {
      OnMemberGone(meta.instance);
    }
  }
  WriterChange change;
  while (reader.TakeWriterChange(change)) {
    if (!change.alive) OnWriterLost(change.writer);
  }
}

}  // namespace handshare::dds
