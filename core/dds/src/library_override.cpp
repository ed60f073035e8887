#include "library_override.hpp"

#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

namespace handshare::dds::detail {

void* LibraryDefinition(const char* symbol, const char* what) {
  void* found = dlsym(RTLD_NEXT, symbol);
  if (found == nullptr) {
    std::fprintf(stderr, "handshare: Fast DDS's %s not found (%s)\n", what, dlerror());
    std::abort();
  }
  return found;
}

bool OverrideInEffect(const char* symbol, void* library_definition) {
  void* resolved = dlsym(RTLD_DEFAULT, symbol);
  Dl_info where{};
  Dl_info library{};
  if (resolved == nullptr || dladdr(resolved, &where) == 0) return false;
  if (dladdr(library_definition, &library) == 0) return false;
  return where.dli_fbase != library.dli_fbase;
}

}  // namespace handshare::dds::detail
