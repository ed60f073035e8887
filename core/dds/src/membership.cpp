#include "handshare/dds/membership.hpp"

#include <sstream>

#include <unistd.h>

#include <chrono>
#include <iostream>

namespace handshare::dds {

MemberAnnouncement::MemberAnnouncement(Participant& participant, const std::string& user,
                                       msg::NodeKind kind, const std::string& device, double view_Hz,
                                       const msg::DeviceCaps& device_caps)
    : writer_(MakeWriter<msg::MemberInfo>(participant, topics::kMemberInfo)) {
  if (user.empty() || user.size() > 40) {
    throw DdsError("member name '" + user + "' must have 1..40 characters");
  }
  char host[64] = {};
  gethostname(host, sizeof(host) - 1);
  info_.member_id(participant.session() + "/" + user);
  info_.session(participant.session());
  info_.user(user);
  info_.kind(kind);
  info_.device(device);
  info_.view_Hz(static_cast<float>(view_Hz));
  info_.device_caps(device_caps);
  info_.host(host);
  info_.pid(static_cast<std::int32_t>(getpid()));
  info_.joined_unix_ns(static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(
          std::chrono::system_clock::now().time_since_epoch()).count()));
  writer_.Write(info_);
}

MemberAnnouncement::~MemberAnnouncement() {
  try {
    // A leave in data first: under load the server may take the dispose only after the writer
    // is gone (the instance then reads "no writers", a loss), and after a partition Fast DDS
    // 2.9 did not deliver the dispose at all; a valid sample carries "left" either way.
    info_.leaving(true);
    writer_.Write(info_);
    writer_.Dispose(info_);
  } catch (const std::exception& e) {
    // A destructor must not throw; the world server then sees the member lost instead.
    std::cerr << "member " << info_.user().c_str() << ": leave not announced: " << e.what() << "\n";
  }
}

const char* ToString(msg::NodeKind kind) {
  switch (kind) {
    case msg::NODE_WORLD_SERVER: return "world_server";
    case msg::NODE_HAPTIC: return "haptic";
    case msg::NODE_GRAPHICS: return "graphics";
    case msg::NODE_AUDIO_GUIDE: return "audio_guide";
  }
  return "unknown";
}

std::string Describe(const msg::DeviceCaps& caps) {
  if (caps.contact_points() == 0) return "";
  static const char* const kNames[] = {"thumb", "index", "middle", "ring", "little"};
  std::ostringstream s;
  s << static_cast<int>(caps.contact_points()) << (caps.contact_points() == 1 ? " point (" : " points (");
  const char* sep = "";
  for (int f = 0; f < 5; ++f) {
    if ((caps.finger_mask() >> f) & 1u) {
      s << sep << kNames[f];
      sep = ", ";
    }
  }
  s << "), " << caps.max_force_N() << " N, workspace " << caps.workspace_radius_m() << " m, " << caps.rate_Hz() << " Hz"
    << (caps.gripper() ? ", gripper" : "");
  return s.str();
}

}  // namespace handshare::dds
