# handshare::warnings: the warning set every target links (INTERFACE, never global flags).
add_library(handshare_warnings INTERFACE)
add_library(handshare::warnings ALIAS handshare_warnings)
target_compile_options(handshare_warnings INTERFACE
  $<$<COMPILE_LANG_AND_ID:CXX,GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
     -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough>)
