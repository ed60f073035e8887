// session_report: what a session log (world_server --log FILE) says about one session.
// Exit codes: 0 report printed, 2 bad arguments or a missing, foreign or corrupt log, 1 other.
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "handshare/common/options.hpp"
#include "handshare/world_server/session_report.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "session_report FILE", "Prints a session of a handshare session log: per control hits, misses and the "
                             "mean and standard deviation of the errors (the paper's Table 4, also by kind of "
                             "control), time spent in each world, the members, the visitors' turns and "
                             "their questionnaires (the paper's Fig. 16). Without --session: the newest session.");
  options.Value("session", "ID", "session id (the log's sessions are numbered from 1)", "")
      .Flag("csv", "print long-format CSV (session,section,item,field,value) instead of tables")
      .Flag("list", "list the sessions in the file");
  // Options knows only --name arguments; FILE is the one positional argument.
  std::vector<const char*> rest{argv[0]};
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0 || arg.empty()) {
      rest.push_back(argv[i]);
      if (arg == "--session" && i + 1 < argc) rest.push_back(argv[++i]);
    } else {
      files.push_back(arg);
    }
  }
  try {
    if (!options.Parse(static_cast<int>(rest.size()), rest.data())) return 0;  // --help
    if (files.size() != 1) {
      throw handshare::common::OptionError(files.empty() ? "missing the session log FILE"
                                                         : "expected one FILE, got " + std::to_string(files.size()));
    }
  } catch (const handshare::common::OptionError& e) {
    std::cerr << "session_report: " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  }
  try {
    if (options.FlagSet("list")) {
      for (const auto& s : handshare::server::ListSessions(files[0])) {
        std::cout << s.id << " '" << s.name << "' domain " << s.domain_id << " started_unix_ns " << s.started_unix_ns
                  << (s.ended_unix_ns ? " ended" : " not ended") << "\n";
      }
      return 0;
    }
    std::optional<std::int64_t> session;
    if (options.Has("session")) session = options.GetInt("session", 1, std::numeric_limits<long>::max());
    const auto report = handshare::server::ReadReport(files[0], session);
    if (options.FlagSet("csv")) {
      handshare::server::PrintReportCsv(std::cout, report);
    } else {
      handshare::server::PrintReport(std::cout, report);
    }
    return 0;
  } catch (const handshare::common::OptionError& e) {
    std::cerr << "session_report: " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  } catch (const handshare::server::SessionLogError& e) {
    std::cerr << "session_report: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "session_report: error: " << e.what() << "\n";
    return 1;
  }
}
