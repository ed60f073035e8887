#pragma once
/// Where handshare's data files are: scenes, meshes and device geometry (assets), QoS profiles,
/// hand scripts.
///
/// An installed executable (PREFIX/bin/NAME, `cmake --install`) finds them under
/// PREFIX/share/handshare, found from /proc/self/exe, so an installed tree runs without the
/// source tree. An executable run from the build tree (no share/handshare beside its folder)
/// finds them in the source tree it was configured from (path compiled in).
///
///   what           installed                        build tree
///   assets         share/handshare/assets           assets
///   QoS profiles   share/handshare/qos              deploy/qos
///   hand scripts   share/handshare/scripts          haptic_node/scripts
#include <filesystem>

namespace handshare::common {

/// PREFIX/share/handshare when the running executable is installed, else empty.
const std::filesystem::path& InstalledDataDir();

/// The assets folder (scenes/, meshes/, devices/): $HANDSHARE_ASSETS if set, else as above.
std::filesystem::path AssetsDir();

/// The folder of the QoS profile files (handshare_qos.xml).
std::filesystem::path QosDir();

/// The folder of the example hand scripts (tour_alice.hand, tour_bob.hand).
std::filesystem::path HandScriptsDir();

}  // namespace handshare::common
