#pragma once
/// Where a shared rigid body is and who holds it, as the world server's tick decides it
/// (ObjectAuthority): plain data, turned into an ObjectState sample only by the DDS publisher
/// (ToObjectState, world_server/src/server_conversions.hpp).
#include <string>

#include <Eigen/Geometry>

namespace handshare::server {

struct BodyState {
  std::string object_id;
  std::string owner;  ///< "" : free (the server simulates it)
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();        ///< pose of body O in world W [m]
  Eigen::Vector3d v_WO_m_per_s = Eigen::Vector3d::Zero();        ///< velocity of O's origin in W
};

}  // namespace handshare::server
