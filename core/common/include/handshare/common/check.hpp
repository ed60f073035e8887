#pragma once
/// Always-on invariant checks: a broken invariant is our bug, so abort with a message.
#include <cstdio>
#include <cstdlib>

#define HS_CHECK(cond, msg)                                                              \
  do {                                                                                   \
    if (!(cond)) {                                                                       \
      std::fprintf(stderr, "%s:%d: check failed: %s: %s\n", __FILE__, __LINE__, #cond,  \
                   (msg));                                                               \
      std::abort();                                                                      \
    }                                                                                    \
  } while (false)
