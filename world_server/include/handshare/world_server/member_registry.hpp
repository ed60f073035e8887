#pragma once
/// Who is in the session: members join (a member-info sample), leave cleanly (disposed) or
/// vanish (no writer alive: killed process, lost network). Pure bookkeeping, no DDS: the
/// world server feeds it what its reader takes.
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace handshare::server {

using InstanceKey = std::array<std::uint8_t, 16>;

struct Member {
  std::string member_id;
  std::string user;
  std::string kind;    // "haptic", "graphics", "audio_guide", "world_server"
  std::string device;  // haptic nodes only
  std::int64_t pid = 0;
  std::string device_caps = {};  // haptic nodes: the device's capabilities in words (dds::Describe)
};

enum class MemberChange { kJoined, kLeft, kLost };

struct MemberEvent {
  MemberChange change;
  Member member;
};

class MemberRegistry {
 public:
  /// A valid member-info sample from `writer`. Returns kJoined the first time it is seen.
  std::optional<MemberEvent> OnInfo(const InstanceKey& key, const InstanceKey& writer,
                                    const Member& member);
  /// The instance was disposed (clean leave) or lost its writers (kill, lost network).
  std::optional<MemberEvent> OnGone(const InstanceKey& key, bool disposed);
  /// A writer went away: every member it announced is lost (if not already gone).
  std::vector<MemberEvent> OnWriterLost(const InstanceKey& writer);
  /// A writer matched again or regained liveliness (a partition healed): the members it had
  /// announced and lost that way are back (kJoined), once each; a writer never lost is ignored.
  std::vector<MemberEvent> OnWriterRegained(const InstanceKey& writer);

  /// Whether a sample that names `user` may have come from `writer`: "" when it may (the user
  /// is not a present member, or its member announcement came from the same participant: the
  /// first 12 bytes of a writer's GUID name its participant), else why not. Without DDS
  /// security nothing stops another station from writing under a present user's name (and
  /// pressing controls, taking bodies in it); a node's writers all live in its one participant.
  std::string CheckAuthor(const std::string& user, const InstanceKey& writer) const;

  std::vector<Member> present() const;
  std::size_t joined_total() const { return joined_total_; }

 private:
  struct Entry {
    Member member;
    InstanceKey writer;
  };
  std::map<InstanceKey, Entry> present_;
  std::map<InstanceKey, Entry> lost_;  // lost with their writer: may come back with it
  std::size_t joined_total_ = 0;
};

const char* ToString(MemberChange change);

}  // namespace handshare::server
