#include "handshare/dds/contact_codec.hpp"

#include <algorithm>
#include <string>

namespace handshare::dds {

using contact::AsVector;

void EncodeFingerContact(const contact::FingerContact& c, std::string_view object_id, double radius_m,
                         double max_displacement_m, msg::FingerContact& out) {
  const bool active = c.active();
  out.active(active);
  out.object_id(active ? std::string(object_id) : std::string());
  out.surface_node(active ? c.node : -1);
  out.radius_m(radius_m);
  if (!active) {
    out.p_OC_m({});
    out.n_O({});
    out.p_OE_m({});
    out.u_O_m({});
    out.f_O_N({});
    out.depth_m(0.0);
    return;
  }
  const Eigen::Vector3d u = AsVector(c.u_O_m);
  const double u_norm = u.norm();
  const Eigen::Vector3d u_sent = u_norm > max_displacement_m ? Eigen::Vector3d(u * (max_displacement_m / u_norm)) : u;
  out.p_OC_m(c.p_OC_m);
  out.n_O(c.n_O);
  out.p_OE_m(c.p_OE_m);
  out.u_O_m(contact::ToVec3(u_sent));
  out.f_O_N(c.f_O_N);
  out.depth_m(std::clamp(c.depth_m, -max_displacement_m, max_displacement_m));
}

bool DecodeFingerContact(const msg::FingerContact& in, std::int32_t finger, contact::ObjectId object,
                         contact::FingerContact& out) noexcept {
  out = contact::FingerContact{};
  out.finger = finger;
  if (!in.active() || object < 0) return false;
  out.object = object;
  out.node = in.surface_node();
  out.p_OC_m = in.p_OC_m();
  out.n_O = in.n_O();
  out.p_OE_m = in.p_OE_m();
  out.u_O_m = in.u_O_m();
  out.f_O_N = in.f_O_N();
  out.depth_m = in.depth_m();
  return true;
}

}  // namespace handshare::dds
