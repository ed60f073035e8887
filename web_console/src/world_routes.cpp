#include "handshare/web_console/world_routes.hpp"

#include <algorithm>

namespace handshare::web_console {

namespace {
// Every event a control of this type can send that may carry an action, with its index.
std::vector<std::pair<controls::EventKind, std::int32_t>> Actuations(const scene::ControlSpec& c) {
  using K = controls::EventKind;
  std::vector<std::pair<K, std::int32_t>> out;
  switch (c.type) {
    case scene::ControlType::kButton:
    case scene::ControlType::kArrow: out.emplace_back(K::kPressed, -1); break;
    case scene::ControlType::kBook:
      out.emplace_back(K::kOpened, 0);
      for (std::int32_t i = 0; i < c.book.pages; ++i) out.emplace_back(K::kPageTurned, i);
      break;
    case scene::ControlType::kLever:
      for (std::int32_t i = 0; i < c.lever.detents; ++i) out.emplace_back(K::kMoved, i);
      break;
  }
  return out;
}

bool Clickable(const scene::ControlSpec& c) {
  return c.type == scene::ControlType::kButton || c.type == scene::ControlType::kArrow;
}
}  // namespace

std::vector<WorldRoute> WorldRoutes(const scene::Scene& scene) {
  std::vector<WorldRoute> routes;
  std::vector<bool> by_click;  // routes[i] goes through a button or an arrow
  for (const scene::ControlSpec& c : scene.controls) {
    for (const auto& [kind, index] : Actuations(c)) {
      const scene::Action* a = controls::ActionOf(c, kind, index);
      if (a == nullptr || a->goto_scene.empty() || a->goto_scene == scene.name) continue;
      WorldRoute r{a->goto_scene, c.id, kind, index};
      const auto it = std::find_if(routes.begin(), routes.end(), [&](const auto& x) { return x.world == r.world; });
      if (it == routes.end()) {
        routes.push_back(std::move(r));
        by_click.push_back(Clickable(c));
      } else if (!by_click[static_cast<std::size_t>(it - routes.begin())] && Clickable(c)) {
        by_click[static_cast<std::size_t>(it - routes.begin())] = true;
        *it = std::move(r);
      }
    }
  }
  return routes;
}

const WorldRoute* FindRoute(const std::vector<WorldRoute>& routes, const std::string& world) noexcept {
  for (const auto& r : routes) {
    if (r.world == world) return &r;
  }
  return nullptr;
}

}  // namespace handshare::web_console
