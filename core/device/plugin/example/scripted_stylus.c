/* An example handshare device plug-in (docs/devices.md): a scripted one-point stylus, the index
 * fingertip, as a 3D Systems Touch or a Novint Falcon would be, moving by itself. Start from it to
 * wrap a real driver: open() talks to the device, read() samples it, command() sends the force.
 *
 *   haptic_node --device "plugin:libhandshare_scripted_stylus.so:press=X,Y,Z period=S depth=M"
 *
 * ARGS, space-separated key=value pairs, positions in the device frame D [m]:
 *   press=X,Y,Z   the point the stylus presses, over and over (default 0,0,0)
 *   period=S      one press: hover 5 cm above, go down, hold, come back up [s] (default 4)
 *   depth=M       how far below the point the tip goes (default 0.008)
 * At close it prints to stderr how many forces it took and the largest, so a test can tell the
 * node's forces reached it. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "handshare/device_plugin.h"

struct hs_device {
  double press[3];
  double period_s;
  double depth_m;
  struct timespec start;
  unsigned long commands;
  double max_force_N;
};

static double Seconds(const struct timespec* a, const struct timespec* b) {
  return (double)(b->tv_sec - a->tv_sec) + 1e-9 * (double)(b->tv_nsec - a->tv_nsec);
}

/* Reads "key=value" pairs; returns 0, or -1 with the reason in error. */
static int ParseArgs(const char* args, struct hs_device* d, char* error, size_t error_size) {
  char buffer[256];
  if (strlen(args) >= sizeof buffer) {
    snprintf(error, error_size, "ARGS longer than %zu characters", sizeof buffer - 1);
    return -1;
  }
  strcpy(buffer, args);
  char* save = NULL;
  for (char* pair = strtok_r(buffer, " ", &save); pair != NULL; pair = strtok_r(NULL, " ", &save)) {
    char* end = NULL;
    if (strncmp(pair, "press=", 6) == 0) {
      if (sscanf(pair + 6, "%lf,%lf,%lf", &d->press[0], &d->press[1], &d->press[2]) != 3) {
        snprintf(error, error_size, "'%s': press takes X,Y,Z in metres", pair);
        return -1;
      }
    } else if (strncmp(pair, "period=", 7) == 0) {
      d->period_s = strtod(pair + 7, &end);
      if (*end != '\0' || !(d->period_s >= 0.5 && d->period_s <= 600.0)) {
        snprintf(error, error_size, "'%s': period takes seconds from 0.5 to 600", pair);
        return -1;
      }
    } else if (strncmp(pair, "depth=", 6) == 0) {
      d->depth_m = strtod(pair + 6, &end);
      if (*end != '\0' || !(d->depth_m >= 0.0 && d->depth_m <= 0.05)) {
        snprintf(error, error_size, "'%s': depth takes metres from 0 to 0.05", pair);
        return -1;
      }
    } else {
      snprintf(error, error_size, "'%s': unknown (press=X,Y,Z period=S depth=M)", pair);
      return -1;
    }
  }
  return 0;
}

static hs_device* Open(const char* args, hs_device_caps* caps, char* error, size_t error_size) {
  struct hs_device* d = calloc(1, sizeof *d);
  if (d == NULL) {
    snprintf(error, error_size, "out of memory");
    return NULL;
  }
  d->period_s = 4.0;
  d->depth_m = 0.008;
  if (ParseArgs(args, d, error, error_size) != 0) {
    free(d);
    return NULL;
  }
  clock_gettime(CLOCK_MONOTONIC, &d->start);
  caps->points = 1;
  caps->finger[0] = HS_INDEX;
  caps->max_force_N[0] = 3.3; /* a Touch's peak force */
  caps->workspace_radius_m = 0.08;
  caps->rate_Hz = 1000.0;
  caps->has_orientation = 0;
  caps->has_gripper = 0;
  snprintf(caps->model, sizeof caps->model, "scripted stylus (example)");
  return d;
}

/* Smooth 0 -> 1 over x in [0, 1]. */
static double Ease(double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  return 0.5 - 0.5 * cos(3.14159265358979323846 * x);
}

static int Read(hs_device* d, hs_device_sample* s) {
  struct timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  const double phase = fmod(Seconds(&d->start, &now), d->period_s) / d->period_s;
  /* A quarter hovering, a quarter going down, a quarter holding, a quarter coming back up. */
  double down = 0.0;
  if (phase < 0.25) {
    down = 0.0;
  } else if (phase < 0.5) {
    down = Ease((phase - 0.25) / 0.25);
  } else if (phase < 0.75) {
    down = 1.0;
  } else {
    down = 1.0 - Ease((phase - 0.75) / 0.25);
  }
  const double hover_m = 0.05;
  s->p_D_m[0][0] = d->press[0];
  s->p_D_m[0][1] = d->press[1];
  s->p_D_m[0][2] = d->press[2] + hover_m - down * (hover_m + d->depth_m);
  return 0;
}

static int Command(hs_device* d, const double f_D_N[HS_DEVICE_MAX_POINTS][3]) {
  const double f = sqrt(f_D_N[0][0] * f_D_N[0][0] + f_D_N[0][1] * f_D_N[0][1] + f_D_N[0][2] * f_D_N[0][2]);
  if (f > d->max_force_N) d->max_force_N = f;
  ++d->commands;
  return 0;
}

static void Close(hs_device* d) {
  fprintf(stderr, "scripted_stylus: %lu forces taken, largest %.3f N\n", d->commands, d->max_force_N);
  free(d);
}

static const hs_device_plugin kPlugin = {HS_DEVICE_ABI_VERSION, 0, "scripted_stylus", Open, Read, Command, Close};

const hs_device_plugin* handshare_device_plugin(void) { return &kPlugin; }
