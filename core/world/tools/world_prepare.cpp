// world_prepare: prepares every deformable of the given scenes (tetgen + FEM compliance) into
// the cache, with a progress bar, so that nodes joining a session find their models ready.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "handshare/common/options.hpp"
#include "handshare/world/deformable_prep.hpp"

int main(int argc, char** argv) {
  using namespace handshare;
  common::Options options("world_prepare",
                          "Precomputes the deformable models of scenes into the compliance cache.");
  options.Value("cache", "DIR", "cache folder", world::DefaultCacheDir().string())
      .Value("scenes", "A,B", "scene names (default: every scene)", "");
  try {
    if (!options.Parse(argc, argv)) return 0;
    std::vector<std::string> names;
    const std::string list = options.GetString("scenes");
    if (list.empty()) {
      for (const auto& e : std::filesystem::directory_iterator(scene::DefaultSceneDir())) {
        if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
      }
      std::sort(names.begin(), names.end());
    } else {
      std::size_t start = 0;
      while (start <= list.size()) {
        const auto comma = list.find(',', start);
        names.push_back(list.substr(start, comma - start));
        if (comma == std::string::npos) break;
        start = comma + 1;
      }
    }
    const std::filesystem::path cache = options.GetString("cache");
    for (const auto& name : names) {
      const scene::Scene s = scene::LoadSceneByName(name);
      for (const auto& o : s.objects) {
        if (o.kind != scene::ObjectKind::kDeformable) continue;
        const auto t0 = std::chrono::steady_clock::now();
        auto progress = [&](std::int64_t done, std::int64_t total) {
          const double f = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
          const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          const int bar = static_cast<int>(f * 30);
          std::fprintf(stderr, "\r  %-24s [%-30s] %3.0f%%  %.0f s left   ", o.id.c_str(),
                       std::string(static_cast<std::size_t>(bar), '#').c_str(), 100 * f,
                       f > 0 ? el * (1 - f) / f : 0.0);
        };
        const auto p = world::PrepareDeformable(s, o, cache, progress);
        std::fprintf(stderr, "\r");
        std::string beat;
        if (p.mode_O_m) {
          double largest = 0.0;
          for (const auto& u : *p.mode_O_m) largest = std::max(largest, u.norm());
          beat = ", " + std::to_string(p.driven_nodes.size()) + " driven (the beat moves it up to " +
                 std::to_string(1e3 * largest).substr(0, 4) + " mm)";
        }
        std::printf("%s/%s: %d nodes, %d tets, %d compliance nodes, %zu fixed%s, %.1f s (%s)\n", name.c_str(),
                    o.id.c_str(), p.mesh->num_nodes(), p.mesh->num_tets(), p.compliance->num_nodes(),
                    p.fixed_nodes.size(), beat.c_str(), p.prepare_s, p.cache_note.c_str());
        std::fflush(stdout);
      }
    }
    return 0;
  } catch (const common::OptionError& e) {
    std::fprintf(stderr, "world_prepare: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "world_prepare: error: %s\n", e.what());
    return 1;
  }
}
