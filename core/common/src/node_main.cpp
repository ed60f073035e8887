#include "handshare/common/node_main.hpp"

#include <exception>
#include <iostream>

#include "handshare/common/shutdown.hpp"

namespace handshare::common {

int RunNodeMain(int argc, const char* const argv[], Options& options,
                const std::function<int(const Options&)>& body) {
  try {
    if (!options.Parse(argc, argv)) return 0;  // --help
  } catch (const OptionError& e) {
    std::cerr << argv[0] << ": " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  }
  InstallShutdownHandlers();
  try {
    return body(options);
  } catch (const OptionError& e) {
    std::cerr << argv[0] << ": " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << argv[0] << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace handshare::common
