/* A device plug-in for tests: a still hand of `points` contact points that misbehaves as its ARGS
 * say, from read number `after` on (0-based). One word of ARGS picks the misbehaviour, further
 * key=value words tune it:
 *   ok            behaves
 *   fail-open     open() fails with a reason
 *   bad-caps      open() states 0 contact points
 *   nan | inf     read() gives a NaN (an infinite) position
 *   jump          read() puts the points 5 cm further from read `after` on, for good
 *   slow          read() takes 3 ms
 *   error         read() returns non-zero
 *   after=N count=C points=P: misbehave at reads after to after + C - 1 (default 0, 1); P contact
 *                 points (1 to 5: thumb, index, ... in that order; default 5)
 * Built three times (tests/CMakeLists of core/device/plugin): as is, with
 * HS_TEST_ABI_VERSION=99 (another ABI version), and with HS_TEST_NO_ENTRY (exports nothing). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "handshare/device_plugin.h"

#ifndef HS_TEST_ABI_VERSION
#define HS_TEST_ABI_VERSION HS_DEVICE_ABI_VERSION
#endif

struct hs_device {
  char mode[32];
  long after;
  long count;
  unsigned points;
  long reads;
};

static hs_device* Open(const char* args, hs_device_caps* caps, char* error, size_t error_size) {
  struct hs_device* d = calloc(1, sizeof *d);
  if (d == NULL) return NULL;
  d->points = 5;
  d->count = 1;
  char buffer[128];
  snprintf(buffer, sizeof buffer, "%s", args);
  char* save = NULL;
  for (char* w = strtok_r(buffer, " ", &save); w != NULL; w = strtok_r(NULL, " ", &save)) {
    if (strncmp(w, "after=", 6) == 0) {
      d->after = strtol(w + 6, NULL, 10);
    } else if (strncmp(w, "count=", 6) == 0) {
      d->count = strtol(w + 6, NULL, 10);
    } else if (strncmp(w, "points=", 7) == 0) {
      d->points = (unsigned)strtoul(w + 7, NULL, 10);
    } else {
      snprintf(d->mode, sizeof d->mode, "%s", w);
    }
  }
  if (strcmp(d->mode, "fail-open") == 0) {
    snprintf(error, error_size, "no device on /dev/test0 (asked to fail)");
    free(d);
    return NULL;
  }
  caps->points = strcmp(d->mode, "bad-caps") == 0 ? 0 : d->points;
  for (unsigned i = 0; i < HS_DEVICE_MAX_POINTS; ++i) {
    caps->finger[i] = i;
    caps->max_force_N[i] = 2.0;
  }
  caps->workspace_radius_m = 0.1;
  caps->rate_Hz = 1000.0;
  snprintf(caps->model, sizeof caps->model, "misbehaving test device");
  return d;
}

static int Read(hs_device* d, hs_device_sample* s) {
  const long n = d->reads++;
  const int now = n >= d->after && n < d->after + d->count;
  const int from_now = n >= d->after;
  for (unsigned i = 0; i < d->points && i < HS_DEVICE_MAX_POINTS; ++i) {
    s->p_D_m[i][0] = 0.02 * (double)i;
    s->p_D_m[i][1] = 0.0;
    s->p_D_m[i][2] = 0.0;
    if (from_now && strcmp(d->mode, "jump") == 0) s->p_D_m[i][2] = 0.05;
  }
  if (now && strcmp(d->mode, "nan") == 0) s->p_D_m[0][1] = NAN;
  if (now && strcmp(d->mode, "inf") == 0) s->p_D_m[0][2] = INFINITY;
  if (now && strcmp(d->mode, "error") == 0) return 1;
  if (now && strcmp(d->mode, "slow") == 0) {
    const struct timespec wait = {0, 3000000};
    nanosleep(&wait, NULL);
  }
  return 0;
}

static int Command(hs_device* d, const double f_D_N[HS_DEVICE_MAX_POINTS][3]) {
  (void)d;
  (void)f_D_N;
  return 0;
}

static void Close(hs_device* d) { free(d); }

#ifndef HS_TEST_NO_ENTRY
static const hs_device_plugin kPlugin = {HS_TEST_ABI_VERSION, 0, "misbehaving", Open, Read, Command, Close};
const hs_device_plugin* handshare_device_plugin(void) { return &kPlugin; }
#else
int handshare_not_a_device_plugin(void) { return (int)sizeof(&Open) + (int)sizeof(&Read) + (int)sizeof(&Command) + (int)sizeof(&Close); }
#endif
