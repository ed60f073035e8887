#pragma once
// A thin RAII layer over the SQLite C API for the session log and its report. Every call is
// checked here, in one place, and a failure becomes a SessionLogError naming the file, the step
// and SQLite's own message. Private to the world_server library.
#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>
#include <string>
#include <string_view>

#include "handshare/world_server/session_log.hpp"

namespace handshare::server::sqlite {

class Db {
 public:
  /// flags: SQLITE_OPEN_READONLY or SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE.
  Db(const std::filesystem::path& file, int flags);
  ~Db();
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;

  sqlite3* get() const { return db_; }
  const std::string& file_name() const { return file_; }

  /// Runs SQL without results (may hold several statements).
  void Exec(const char* sql, const char* what);
  /// Runs a statement that returns one value (PRAGMA x, SELECT count(*)).
  std::int64_t QueryInt(const char* sql, const char* what);
  std::string QueryText(const char* sql, const char* what);

  /// Throws SessionLogError: "<file>: <what>: <sqlite message>".
  [[noreturn]] void Fail(int rc, std::string_view what) const;
  /// rc must be SQLITE_OK (or ROW / DONE, the results of a step).
  void Check(int rc, std::string_view what) const {
    if (rc != SQLITE_OK && rc != SQLITE_ROW && rc != SQLITE_DONE) Fail(rc, what);
  }

 private:
  std::string file_;
  sqlite3* db_ = nullptr;
};

class Statement {
 public:
  Statement(Db& db, const char* sql, const char* what);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& Bind(int index, std::int64_t value);
  Statement& Bind(int index, double value);
  Statement& Bind(int index, std::string_view text);
  Statement& Bind(int index, const std::optional<double>& value);
  Statement& BindNull(int index);
  Statement& BindBlob(int index, std::span<const std::uint8_t> bytes);

  /// Returns true while there is a row, false when done. Throws on an error.
  bool Step();
  /// Ready for the next bindings.
  void Reset();

  std::int64_t Int(int column) const;
  double Double(int column) const;
  std::string Text(int column) const;
  bool IsNull(int column) const;
  std::vector<std::uint8_t> Blob(int column) const;
  /// The statement itself, for what this wrapper does not cover.
  sqlite3_stmt* get() const { return stmt_; }

 private:
  Db& db_;
  const char* what_;
  sqlite3_stmt* stmt_ = nullptr;
};

}  // namespace handshare::server::sqlite
