#include "pose_trace.hpp"

#include <iomanip>

#include "handshare/common/clock.hpp"

namespace handshare::server {

PoseTrace::PoseTrace(std::ostream& out, std::function<std::uint64_t()> steady_now)
    : out_(out), steady_now_(steady_now ? std::move(steady_now) : std::function<std::uint64_t()>(common::SteadyNowNs)) {
  out_ << "stamp_ns,object_id,owner,x_m,y_m,z_m,vx_m_per_s,vy_m_per_s,vz_m_per_s\n" << std::setprecision(9);
  out_.flush();
}

void PoseTrace::Take(std::span<const SessionEvent> events, Clock::time_point /*now*/) {
  bool any = false;
  std::uint64_t stamp_ns = 0;
  for (const SessionEvent& event : events) {
    const auto* e = std::get_if<BodyMoved>(&event);
    if (e == nullptr) continue;
    if (!any) stamp_ns = steady_now_();
    any = true;
    const BodyState& b = e->body;
    out_ << stamp_ns << ',' << b.object_id << ',' << b.owner;
    for (int k = 0; k < 3; ++k) out_ << ',' << b.X_WO.translation()[k];
    for (int k = 0; k < 3; ++k) out_ << ',' << b.v_WO_m_per_s[k];
    out_ << '\n';
  }
  if (any) out_.flush();
}

}  // namespace handshare::server
