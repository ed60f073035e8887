// Fast DDS 2.9.1's lease-check race and the guard against it (src/lease_race_guard.cpp), over
// real participants in a helper process (lease_race_helper.cpp) whose lease checks start late.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "../src/lease_race_guard.hpp"

namespace handshare::dds {
namespace {

using namespace std::chrono_literals;

struct HelperRun {
  int status = 0;
  bool finished = false;
  std::string out, err;
};

std::string ReadAll(const std::string& path) {
  std::ifstream f(path);
  std::stringstream text;
  text << f.rdbuf();
  return text.str();
}

// Runs `helper DOMAIN SECONDS`, killing it after `limit`.
HelperRun RunHelper(const char* helper, int domain, double seconds, std::chrono::seconds limit) {
  const std::string base = "/tmp/lease_race_" + std::to_string(getpid()) + "_" + std::to_string(domain);
  HelperRun run;
  const pid_t pid = fork();
  if (pid == 0) {
    const rlimit no_core{0, 0};  // the control's abort is expected: no core file
    setrlimit(RLIMIT_CORE, &no_core);
    if (!freopen((base + ".out").c_str(), "w", stdout) || !freopen((base + ".err").c_str(), "w", stderr)) _exit(126);
    const std::string d = std::to_string(domain), s = std::to_string(seconds);
    execl(helper, helper, d.c_str(), s.c_str(), nullptr);
    _exit(127);
  }
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (waitpid(pid, &run.status, WNOHANG) == pid) {
      run.finished = true;
      break;
    }
    std::this_thread::sleep_for(20ms);
  }
  if (!run.finished) {
    kill(pid, SIGKILL);
    waitpid(pid, &run.status, 0);
  }
  run.out = ReadAll(base + ".out");
  run.err = ReadAll(base + ".err");
  std::remove((base + ".out").c_str());
  std::remove((base + ".err").c_str());
  return run;
}

TEST(LeaseRace, TheGuardIsInEffectInAProcessThatLinksTheDdsLayer) {
  EXPECT_TRUE(detail::LeaseRaceGuardActive());
}

// The control: without the guard, a peer removed while its lease check waits for the mutex
// aborts the process in Fast DDS's assertion (typically within a second here).
TEST(LeaseRace, WithoutTheGuardAPeerLeavingDuringItsLeaseCheckAbortsTheProcess) {
  const HelperRun run = RunHelper(HANDSHARE_LEASE_RACE_HELPER_UNGUARDED, 160, 30.0, 60s);
  ASSERT_TRUE(run.finished) << "the unguarded helper did not end within 60 s";
  EXPECT_NE(run.out.find("guard absent"), std::string::npos) << run.out;
  ASSERT_TRUE(WIFSIGNALED(run.status) && WTERMSIG(run.status) == SIGABRT)
      << "the race was not met in 30 s (exit status " << run.status << "): " << run.out << run.err;
  EXPECT_NE(run.err.find("check_remote_participant_liveliness"), std::string::npos) << run.err;
}

// The same departures with the guard: no abort.
TEST(LeaseRace, WithTheGuardPeersLeaveDuringTheirLeaseChecksAndNothingAborts) {
  const HelperRun run = RunHelper(HANDSHARE_LEASE_RACE_HELPER, 161, 3.0, 60s);
  ASSERT_TRUE(run.finished) << "the guarded helper did not end within 60 s";
  EXPECT_NE(run.out.find("guard active"), std::string::npos) << run.out;
  ASSERT_TRUE(WIFEXITED(run.status) && WEXITSTATUS(run.status) == 0)
      << "exit status " << run.status << ": " << run.out << run.err;
  EXPECT_NE(run.out.find("survived"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace handshare::dds
