// A reliable message-board reader in a process of its own, for tests that need a peer they can
// stop (SIGSTOP) while it stays matched: reliable_reader_helper DOMAIN SESSION. Prints "ready"
// once it exists, takes whatever arrives, and leaves cleanly on SIGTERM or when its parent exits.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "handshare/common/shutdown.hpp"
#include "handshare/dds/messages.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: reliable_reader_helper DOMAIN SESSION\n");
    return 2;
  }
  using namespace handshare::dds;
  handshare::common::InstallShutdownHandlers();
  Participant p(std::atoi(argv[1]), argv[2], "reliable_reader_helper");
  auto reader = MakeReader<handshare::msg::MessageBoard>(p, topics::kMessageBoard);
  std::printf("ready\n");
  std::fflush(stdout);
  handshare::msg::MessageBoard board;
  SampleMeta meta;
  const pid_t parent = getppid();
  while (getppid() == parent && !handshare::common::ShutdownRequested()) {
    while (reader.TakeNext(board, meta)) {
    }
    reader.WaitForData(std::chrono::milliseconds(50));
  }
  return 0;
}
