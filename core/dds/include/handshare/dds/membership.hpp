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
  /// @param device  "sim", "hiro", "replay", "desk", "plugin:<name>" for haptic nodes, "" otherwise.
  /// @param view_Hz graphics nodes: how often they read device states (their frame rate).
  /// @param device_caps haptic nodes: what their device is (contact points, fingers, limits).
  MemberAnnouncement(Participant& participant, const std::string& user, msg::NodeKind kind,
                     const std::string& device = "", double view_Hz = 0.0, const msg::DeviceCaps& device_caps = {});
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
/// A device's capabilities in words: "1 point (index), 3.3 N, workspace 0.08 m, 1000 Hz";
/// "" for none (contact_points 0).
std::string Describe(const msg::DeviceCaps& caps);

}  // namespace handshare::dds
