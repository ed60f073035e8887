#pragma once
/// Who may write in a user's name: the participant that announced the user (its MemberInfo on
/// handshare/member_info). DDS-Security's grants are per topic, not per instance, so any
/// haptic user may write contact sets and control events with any user name; a node that
/// binds each present user's name to the participant that announced it can drop samples in
/// that name from every other participant (docs/security.md, "What is protected and what is
/// not"). A name nobody present has announced is not bound (it is anybody's).
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "handshare/dds/messages.hpp"

namespace handshare::dds {

/// A DDS GUID as SampleMeta gives it: 12 bytes of participant prefix, then the entity.
using Guid = std::array<std::uint8_t, 16>;

/// Whether two endpoints' GUIDs belong to the same participant.
bool SameParticipant(const Guid& a, const Guid& b);
/// The participant prefix in hex (24 characters), for messages.
std::string ParticipantOf(const Guid& endpoint);
/// Why a sample in `user`'s name from `writer` is refused, the user having joined from
/// `announced`: "user 'alice' joined from participant X, this sample came from participant Y".
std::string AuthorMismatch(const std::string& user, const Guid& announced, const Guid& writer);

/// The graphics nodes present and the fastest frame rate among them (MemberInfo::view_Hz).
struct Viewers {
  int count = 0;
  double fastest_Hz = 0.0;
};

class NameBinding {
 public:
  /// A live member sample: member `instance` (its key hash) is `user`, announced by `writer`;
  /// a graphics node gives its frame rate (view_Hz), other nodes 0; a haptic node its device.
  void OnMember(const Guid& instance, const std::string& user, const Guid& writer, msg::NodeKind kind = msg::NODE_HAPTIC,
                double view_Hz = 0.0, const std::string& device = "");
  /// Member `instance` left (disposed) or has no writer any more.
  void OnMemberGone(const Guid& instance);
  /// A member_info writer went away (killed or lost): the members it announced are gone.
  void OnWriterLost(const Guid& writer);
  /// Empty if `writer` may write in `user`'s name, else why not (AuthorMismatch).
  std::string Check(const std::string& user, const Guid& writer) const;

  /// A member_info reader for a node that binds names. Under DDS-Security a keystore made
  /// before its role was granted member_info refuses the reader: then `say` is told, and the
  /// reader is empty (the node joins, its peers' names unbound).
  static Reader<msg::MemberInfo> MakeMemberReader(Participant& participant,
                                                       const std::function<void(const std::string&)>& say);
  /// Takes every member sample and lost member writer of `reader` (empty: nothing).
  void Follow(Reader<msg::MemberInfo>& reader);
  std::size_t size() const { return members_.size(); }
  /// The names of the present members (users and nodes), each once.
  std::vector<std::string> users() const;
  /// The device a present user announced ("sim", "hiro", "replay"), "" if none or not present.
  std::string DeviceOf(const std::string& user) const;
  /// The present graphics nodes, for a writer of device states that sends only as often as
  /// the fastest of them draws.
  Viewers viewers() const;

 private:
  struct Member {
    std::string user;
    Guid writer{};
    msg::NodeKind kind = msg::NODE_HAPTIC;
    double view_Hz = 0.0;
    std::string device;
  };
  std::map<Guid, Member> members_;
};

}  // namespace handshare::dds
