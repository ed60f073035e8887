// Fuzz target: a scene file (JSON) read by scene::LoadScene, the meshes it names only checked
// for existence (a fuzzed path must not send assimp reading devices or large files). The file
// lies in a scenes/ folder beside a meshes/ link to the project's meshes, as in assets/, and
// among links to the project's scenes, so the project's scenes, as seeds, name meshes and
// scenes (a control's goto) that exist, and are read to the end.
#include <filesystem>

#include "fuzz_support.hpp"
#include "handshare/scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool linked = [] {
    const auto dir = handshare::fuzz::WriteInput("scenes/.keep", nullptr, 0).parent_path().parent_path();
    std::filesystem::create_directory_symlink(HANDSHARE_FUZZ_ASSETS "/meshes", dir / "meshes");
    for (const auto& e : std::filesystem::directory_iterator(HANDSHARE_FUZZ_ASSETS "/scenes")) {
      std::filesystem::create_symlink(e.path(), dir / "scenes" / e.path().filename());
    }
    return true;
  }();
  (void)linked;
  const auto file = handshare::fuzz::WriteInput("scenes/fuzzed_input.json", data, size);
  handshare::fuzz::ExpectOnly<handshare::scene::SceneError>(
      [&] { handshare::scene::LoadScene(file, handshare::scene::LoadOptions{.load_meshes = false}); });
  return 0;
}
