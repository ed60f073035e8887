/* handshare device plug-in ABI, version 1 (docs/devices.md).
 *
 * A lab's haptic device reaches handshare as a shared library that exports one C function,
 * `handshare_device_plugin`, returning a table of functions. `haptic_node --device
 * plugin:PATH.so[:ARGS]` loads it with dlopen, checks the table's ABI version, opens the device
 * with ARGS, and then, on its haptic thread at the loop's rate (1 kHz by default), calls read()
 * and command() once per step each.
 *
 * Frame D, the device's frame: x to the user's right, y away from the user, z up, origin at the
 * centre of the device's workspace, metres. The node places D in the world (W has the same axes)
 * at a point of its choosing (`--device-origin`, `--device-scale`). Forces are in D's axes in
 * newtons, the force on the user's fingertip.
 *
 * Contact points. A device has 1 to 5 contact points, each one fingertip of the hand: a
 * one-point device (3D Systems Touch, Novint Falcon) is usually the index finger, a two-point one
 * (an omega.7's gripper) thumb and index, HIRO II all five. The node simulates exactly the
 * fingers the device has; the others do not exist for it (no stand-ins).
 *
 * Rules for read() and command(): they run on the haptic thread and must be real-time safe: no
 * blocking I/O, no locks that another thread holds for long, no allocation, return within the
 * deadline (half a period by default, `--device-deadline-us`). A call that returns non-zero,
 * gives a non-finite or a jumping position, or overruns the deadline is a device fault: the node
 * counts it and ramps every force to zero (and back once the data is good again). open() and
 * close() run on the node's main thread and may block.
 *
 * Versioning: HS_DEVICE_ABI_VERSION changes whenever a struct or a function of this header
 * changes; the node refuses a plug-in built with another version, with a message naming both.
 * Structs are plain C with fixed-size types; the plug-in fills them, the node zeroes them first.
 */
#ifndef HANDSHARE_DEVICE_PLUGIN_H
#define HANDSHARE_DEVICE_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HS_DEVICE_ABI_VERSION 1u
#define HS_DEVICE_MAX_POINTS 5
/* The one symbol a plug-in exports. */
#define HS_DEVICE_ENTRY_NAME "handshare_device_plugin"

/* Which finger a contact point is. */
enum hs_finger { HS_THUMB = 0, HS_INDEX = 1, HS_MIDDLE = 2, HS_RING = 3, HS_LITTLE = 4 };

/* What a device is, stated by open(): IEEE 1918.1.1's capability exchange in small. The node
 * publishes it with its member, so every screen draws the hand the user really has. */
typedef struct hs_device_caps {
  uint32_t points;                               /* contact points, 1 to HS_DEVICE_MAX_POINTS */
  uint32_t finger[HS_DEVICE_MAX_POINTS];         /* point i is finger finger[i] (enum hs_finger), all different */
  double max_force_N[HS_DEVICE_MAX_POINTS];      /* continuous force point i can display [N], > 0 */
  double workspace_radius_m;                     /* the points reach a sphere this big around D's origin [m], > 0 */
  double rate_Hz;                                /* the rate the device is meant to run at [Hz], > 0 */
  uint32_t has_orientation;                      /* 1: read() gives the handle's orientation */
  uint32_t has_gripper;                          /* 1: read() gives a gripper angle */
  char model[64];                                /* shown to users, e.g. "Novint Falcon"; NUL-terminated */
} hs_device_caps;

/* One reading, filled by read(). */
typedef struct hs_device_sample {
  double p_D_m[HS_DEVICE_MAX_POINTS][3]; /* contact point i (caps.finger[i]) in D [m]; i < caps.points */
  double q_D_wxyz[4];                    /* the handle's orientation in D (has_orientation; else ignored) */
  double gripper_rad;                    /* gripper opening [rad] (has_gripper; else ignored) */
} hs_device_sample;

typedef struct hs_device hs_device; /* the plug-in's own state, opaque to the node */

typedef struct hs_device_plugin {
  uint32_t abi_version; /* HS_DEVICE_ABI_VERSION as the plug-in was compiled */
  uint32_t reserved;    /* 0 */
  const char* name;     /* short name, e.g. "falcon"; the member's device reads "plugin:<name>" */
  /* Opens the device with the text after PATH.so: in --device plugin:PATH.so[:ARGS] (maybe "").
   * Fills caps. Returns the device, or NULL and a NUL-terminated reason in error[error_size]. */
  hs_device* (*open)(const char* args, hs_device_caps* caps, char* error, size_t error_size);
  /* Samples the device. Returns 0, or non-zero when the data is not trustworthy now. */
  int (*read)(hs_device* device, hs_device_sample* sample);
  /* Displays the forces on the contact points (row i: point i) [N], already clamped to
   * max_force_N and rate-bounded by the node. Returns 0, or non-zero on a device error. */
  int (*command)(hs_device* device, const double f_D_N[HS_DEVICE_MAX_POINTS][3]);
  /* Forces to zero and releases the device. */
  void (*close)(hs_device* device);
} hs_device_plugin;

/* The type of the exported function `handshare_device_plugin`. */
typedef const hs_device_plugin* (*hs_device_plugin_entry)(void);

#ifdef __cplusplus
}
#endif

#endif /* HANDSHARE_DEVICE_PLUGIN_H */
