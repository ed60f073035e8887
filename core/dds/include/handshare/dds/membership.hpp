#pragma once
/// Membership of a session: every node announces itself on the member-info topic when it
/// starts and disposes its entry when it ends cleanly. A node that is killed stops asserting
/// liveliness, and the world server sees its instance lose all writers.
#include <string>

#include "handshare/dds/messages.hpp"

namespace handshare::dds {

class MemberAnnouncement {
 public:
  /// @param user    user name (haptic nodes) or node name (others); unique in the session.
  /// @param kind    what the node is.
  /// @param device  "sim", "hiro", "replay" for haptic nodes, "" otherwise.
  /// @param view_Hz graphics nodes: how often they read device states (their frame rate).
  MemberAnnouncement(Participant& participant, const std::string& user, msg::NodeKind kind,
                     const std::string& device = "", double view_Hz = 0.0);
  /// Disposes the member entry: a clean leave.
  ~MemberAnnouncement();
  MemberAnnouncement(const MemberAnnouncement&) = delete;
  MemberAnnouncement& operator=(const MemberAnnouncement&) = delete;

  const msg::MemberInfo& info() const { return info_; }

 private:
  Writer<msg::MemberInfo> writer_;
  msg::MemberInfo info_;
};

const char* ToString(msg::NodeKind kind);

}  // namespace handshare::dds
