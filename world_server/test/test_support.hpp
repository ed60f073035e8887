#pragma once
// Helpers shared by the world server's tests: a fresh folder per test under $TMPDIR, removed
// (permissions restored first) at the end; fixed times; the message of a SessionLogError; a
// log's values read back with sqlite3 alone (an independent reader); the scenes the tests build
// (messages, controls, a world, the Moon's ball scene as a file).
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "handshare/scene/scene.hpp"
#include "handshare/world_server/session_log.hpp"

namespace handshare::server::testing {

class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "handshare_ws_XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed for " + pattern);
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::permissions(path_, std::filesystem::perms::owner_all, ec);
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

inline constexpr std::uint64_t kT0 = 1'700'000'000'000'000'000ULL;  // a fixed Unix time [ns]
inline constexpr std::uint64_t kSecond = 1'000'000'000ULL;

/// what() of the SessionLogError that f throws, or "<no SessionLogError>".
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const SessionLogError& e) {
    return e.what();
  }
  return "<no SessionLogError>";
}

/// Runs `sql` on the log `file` (read-only, sqlite3 alone) and calls row(statement) on its
/// first row. False when there is no row; a statement that does not prepare is a test failure.
inline bool QueryFirstRow(const std::filesystem::path& file, const std::string& sql,
                          const std::function<void(sqlite3_stmt*)>& row) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* s = nullptr;
  bool found = false;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
  } else if (sqlite3_step(s) == SQLITE_ROW) {
    row(s);
    found = true;
  }
  sqlite3_finalize(s);
  sqlite3_close(db);
  return found;
}

/// One text value of `sql` in `file` ("<none>": no row, "<null>": NULL).
inline std::string Query(const std::filesystem::path& file, const std::string& sql) {
  std::string out = "<none>";
  QueryFirstRow(file, sql, [&](sqlite3_stmt* s) {
    const auto* t = sqlite3_column_text(s, 0);
    out = t ? reinterpret_cast<const char*>(t) : "<null>";
  });
  return out;
}

/// One integer value of `sql` in `file`; a missing row is a test failure (and -1).
inline std::int64_t QueryInt(const std::filesystem::path& file, const std::string& sql) {
  std::int64_t v = -1;
  if (!QueryFirstRow(file, sql, [&](sqlite3_stmt* s) { v = sqlite3_column_int64(s, 0); })) {
    ADD_FAILURE() << sql << ": no row";
  }
  return v;
}

/// A board message (a Japanese one with a kana reading, as the scene loader requires).
inline scene::Message Msg(const std::string& language, const std::string& text) {
  return {language, text, "", language == "ja" ? "よみ" : ""};
}

inline scene::ControlSpec Control(const std::string& id, scene::ControlType type) {
  scene::ControlSpec c;
  c.id = id;
  c.type = type;
  return c;
}

/// A world named `name` under gravity g [m/s^2] down, with an English and a Japanese message.
inline scene::Scene World(const std::string& name, double g) {
  scene::Scene s;
  s.name = name;
  s.title = name + " title";
  s.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -g);
  s.messages = {Msg("en", "welcome to " + name), Msg("ja", name + " ja")};
  return s;
}

/// The ball scene, written as dir/scenes/NAME.json: a ground box and a 0.2 kg ball of radius
/// 4 cm resting on it, under gravity g_z [m/s^2] (the Moon's by default).
inline std::filesystem::path WriteBallScene(const std::filesystem::path& dir, const std::string& name = "moon",
                                            double g_z = -1.62) {
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / (name + ".json");
  std::ofstream(file) << R"({"name": ")" << name << R"(", "gravity_m_per_s2": [0, 0, )" << g_z << R"(], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
      {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [0, 0, 0.04], "radius_m": 0.04, "mass_kg": 0.2}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  return file;
}

}  // namespace handshare::server::testing
