# handshare::warnings: the warning set every target links (INTERFACE, never global flags).
add_library(handshare_warnings INTERFACE)
add_library(handshare::warnings ALIAS handshare_warnings)
target_compile_options(handshare_warnings INTERFACE
  $<$<COMPILE_LANG_AND_ID:CXX,GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
     -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough>)

# Warnings as errors (the `ci` preset, and deploy/build.sh, turn it on): every target that links
# handshare::warnings fails to build on a warning. Generated code (idl) does not link it.
option(HANDSHARE_WARNINGS_AS_ERRORS "Treat compiler warnings as errors in every handshare target" OFF)
if(HANDSHARE_WARNINGS_AS_ERRORS)
  target_compile_options(handshare_warnings INTERFACE $<$<COMPILE_LANG_AND_ID:CXX,GNU,Clang>:-Werror>)
endif()
