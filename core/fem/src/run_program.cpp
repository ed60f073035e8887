#include "run_program.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "handshare/fem/error.hpp"

extern char** environ;

namespace handshare::fem::detail {

std::string Tail(const std::filesystem::path& file, std::size_t max_chars) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  return s;
}

int RunProgram(const std::vector<std::string>& args, const std::filesystem::path& cwd,
               const std::filesystem::path& log, const std::string& package) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log_s = log.string();
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_s.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  const std::string cwd_s = cwd.string();
  // The child must run in cwd (tetgen and ccx write next to their input); glibc 2.29+.
  posix_spawn_file_actions_addchdir_np(&actions, cwd_s.c_str());
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw FemError("cannot run '" + args[0] + "': " + std::strerror(rc) +
                   (rc == ENOENT ? " (install the Debian package " + package + ")" : ""));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw FemError("waitpid failed for '" + args[0] + "'");
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

}  // namespace handshare::fem::detail
