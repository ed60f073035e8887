#include "sqlite_db.hpp"

#include <limits>

namespace handshare::server::sqlite {

Db::Db(const std::filesystem::path& file, int flags) : file_(file.string()) {
  const int rc = sqlite3_open_v2(file_.c_str(), &db_, flags | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    // The handle exists even on failure (unless out of memory): take its message, then close.
    std::string message = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    std::string what = (flags & SQLITE_OPEN_CREATE) ? "cannot open or create the session log"
                                                    : "cannot open the session log";
    if ((rc & 0xff) == SQLITE_CANTOPEN) what += " (does its folder exist, and may we write there?)";
    throw SessionLogError(file_ + ": " + what + ": " + message);
  }
  Check(sqlite3_extended_result_codes(db_, 1), "enabling extended result codes");
}

Db::~Db() {
  // Statements are finalized by their owners first; close_v2 defers if any remain.
  sqlite3_close_v2(db_);
}

void Db::Fail(int rc, std::string_view what) const {
  std::string message = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
  // errmsg describes the most recent failure on this handle; if another call has since
  // succeeded it says "not an error", so fall back to the text of rc itself.
  if (message == "not an error") message = sqlite3_errstr(rc);
  throw SessionLogError(file_ + ": " + std::string(what) + ": " + message);
}

void Db::Exec(const char* sql, const char* what) {
  char* error = nullptr;
  const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &error);
  if (rc != SQLITE_OK) {
    std::string message = error ? error : sqlite3_errstr(rc);
    sqlite3_free(error);
    throw SessionLogError(file_ + ": " + what + ": " + message);
  }
}

std::int64_t Db::QueryInt(const char* sql, const char* what) {
  Statement s(*this, sql, what);
  if (!s.Step()) throw SessionLogError(file_ + ": " + what + ": no result");
  return s.Int(0);
}

std::string Db::QueryText(const char* sql, const char* what) {
  Statement s(*this, sql, what);
  if (!s.Step()) throw SessionLogError(file_ + ": " + what + ": no result");
  return s.Text(0);
}

Statement::Statement(Db& db, const char* sql, const char* what) : db_(db), what_(what) {
  db_.Check(sqlite3_prepare_v2(db_.get(), sql, -1, &stmt_, nullptr), what_);
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::Bind(int index, std::int64_t value) {
  db_.Check(sqlite3_bind_int64(stmt_, index, value), what_);
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  db_.Check(sqlite3_bind_double(stmt_, index, value), what_);
  return *this;
}

Statement& Statement::Bind(int index, std::string_view text) {
  if (text.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    db_.Fail(SQLITE_TOOBIG, what_);
  }
  db_.Check(sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT),
            what_);
  return *this;
}

Statement& Statement::Bind(int index, const std::optional<double>& value) {
  return value ? Bind(index, *value) : BindNull(index);
}

Statement& Statement::BindNull(int index) {
  db_.Check(sqlite3_bind_null(stmt_, index), what_);
  return *this;
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  db_.Fail(rc, what_);
}

void Statement::Reset() {
  // reset returns the error of the last step again, which Step() has already thrown.
  sqlite3_reset(stmt_);
  db_.Check(sqlite3_clear_bindings(stmt_), what_);
}

std::int64_t Statement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }
double Statement::Double(int column) const { return sqlite3_column_double(stmt_, column); }
std::string Statement::Text(int column) const {
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
  if (!text) return {};
  return std::string(text, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
}
bool Statement::IsNull(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
std::vector<std::uint8_t> Statement::Blob(int column) const {
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_, column));
  if (!data) return {};
  return std::vector<std::uint8_t>(data, data + sqlite3_column_bytes(stmt_, column));
}
Statement& Statement::BindBlob(int index, std::span<const std::uint8_t> bytes) {
  db_.Check(sqlite3_bind_blob64(stmt_, index, bytes.data(), bytes.size(), SQLITE_TRANSIENT), what_);
  return *this;
}

}  // namespace handshare::server::sqlite
