/*
 * overtake planner plugins: the C ABI.
 *
 * A plugin is a shared library that defines the five functions declared at the end of this
 * header. `overtake drive|bench|serve --policy-lib [NAME=]PATH` loads it (dlopen), checks
 * that every function is there and that overtake_plugin_abi_version() returns
 * OVERTAKE_PLUGIN_ABI_VERSION, and then runs it in-process like a built-in policy: one
 * handle per run (drive, each bench run, each `serve` connection), one call of
 * overtake_plugin_plan per telemetry message.
 *
 * What the planner sees is what the original Udacity Term 3 simulator sends over its
 * websocket, field for field and in the same units (metres, DEGREES for yaw, MPH for the
 * ego's speed, m/s for the other cars' velocities), rounded as the original's wire rounds
 * numbers (32-bit floats, 7 significant digits). A planner written for the original ports
 * over by replacing its JSON parsing with these structs.
 *
 * Pure C (C99 and later) and C++. Only fixed-size types and pointers cross the boundary.
 *
 * Threads: a bench runs several runs at once, so different handles may be used at the same
 * time from different threads. Keep every piece of state in the handle (no mutable globals).
 * One handle is only ever used by one thread at a time.
 *
 * Exceptions: do not let a C++ exception leave these functions. (overtake catches one that
 * does and ends the run as planner_failed, but unwinding through a C interface is not
 * something to rely on.) Report failures with a nonzero status and an error message.
 */
#ifndef OVERTAKE_PLANNER_PLUGIN_H
#define OVERTAKE_PLANNER_PLUGIN_H

#include <stddef.h>

/* The version of this ABI. A plugin returns it from overtake_plugin_abi_version(); overtake
 * refuses a plugin that returns another number. Any change to a struct or a function
 * signature below changes it. */
#define OVERTAKE_PLUGIN_ABI_VERSION 1

#ifdef __cplusplus
#define OVERTAKE_PLUGIN_EXTERN_C extern "C"
#else
#define OVERTAKE_PLUGIN_EXTERN_C
#endif

/* Marks the plugin's functions for export, also when it is built with
 * -fvisibility=hidden. */
#if defined(__GNUC__) || defined(__clang__)
#define OVERTAKE_PLUGIN_EXPORT OVERTAKE_PLUGIN_EXTERN_C __attribute__((visibility("default")))
#else
#define OVERTAKE_PLUGIN_EXPORT OVERTAKE_PLUGIN_EXTERN_C
#endif

/* Column indices of a sensor-fusion row, as in the original: [id, x, y, vx, vy, s, d]. */
#define OVERTAKE_SF_ID 0
#define OVERTAKE_SF_X 1
#define OVERTAKE_SF_Y 2
#define OVERTAKE_SF_VX 3
#define OVERTAKE_SF_VY 4
#define OVERTAKE_SF_S 5
#define OVERTAKE_SF_D 6
#define OVERTAKE_SF_COLUMNS 7

/* The plugin's name and a one-line description. */
typedef struct overtake_plugin_info_t {
  /* Letters, digits, '_', '-', '.': the planner's name in reports and bench tables (unless
   * the user names it with NAME=). Not NULL, not empty. */
  const char* name;
  /* One line saying what the planner does (may be NULL or empty). */
  const char* summary;
} overtake_plugin_info_t;

/* One line of the map file (highway_map.csv in the original): the road's divider (the
 * left edge of the leftmost lane) at distance s along the road. */
typedef struct overtake_waypoint {
  double x;  /* m, map axes */
  double y;  /* m */
  double s;  /* m along the road from the map's start */
  double dx; /* unit normal, pointing away from the divider (towards increasing d) */
  double dy;
} overtake_waypoint;

/* What a plugin is given once per handle. Everything it points to is valid only during the
 * call of overtake_plugin_create: copy what you keep. */
typedef struct overtake_plugin_setup {
  /* The map's waypoints, in the map's order (181 for the original's highway_map.csv). */
  const overtake_waypoint* waypoints;
  size_t waypoint_count;
  /* m: the loop's length; s wraps from max_s back to the first waypoint's s (6945.554 on
   * the original's map). */
  double max_s;
  /* Lanes left to right, lane i centred at d = lane_width * (i + 0.5) (3 lanes of 4 m in
   * the original: centres at d = 2, 6, 10). */
  int lane_count;
  double lane_width; /* m */
  /* s: the simulator's step, the time between two consecutive path points (0.02). */
  double step_time;
  /* A JSON text the user passed for this plugin, or NULL when none (reserved: this version
   * of overtake always passes NULL). */
  const char* config_json;
} overtake_plugin_setup;

/* One telemetry message, as the original sends it (its keys, its units). Everything it
 * points to is valid only during the call of overtake_plugin_plan. */
typedef struct overtake_telemetry {
  double x;     /* m: the ego's position, map axes */
  double y;     /* m */
  double s;     /* m: Frenet s of the ego (measured on the straight chords between waypoints,
                   as the original does) */
  double d;     /* m: Frenet d of the ego, from the divider (lane i: lane_width*i .. *(i+1)) */
  double yaw;   /* DEGREES, counter-clockwise from +x, in [0, 360) */
  double speed; /* MPH (the ego's distance in the last step over the step time) */
  /* The points of the last path this planner sent that the car has not driven yet, in
   * driving order (x[i], y[i]), m. Empty (count 0) at the start. */
  const double* previous_path_x;
  const double* previous_path_y;
  size_t previous_path_count;
  /* m: Frenet s and d of the last point of previous_path; both 0 when it is empty. */
  double end_path_s;
  double end_path_d;
  /* The other cars, one row each: [id, x, y, vx, vy, s, d] (see OVERTAKE_SF_*): id (a whole
   * number), position in m, velocity in M/S in map axes (not mph), Frenet s and d in m. */
  const double (*sensor_fusion)[OVERTAKE_SF_COLUMNS];
  size_t sensor_fusion_count;
} overtake_telemetry;

/* The path a planner answers: the points the ego drives through, one per step_time, in
 * driving order (the original's next_x, next_y). overtake provides the buffers: write into
 * them (replacing the pointers fails the cycle). */
typedef struct overtake_path {
  double* next_x;  /* in: a buffer of `capacity` doubles; out: x of the points, m */
  double* next_y;  /* in: a buffer of `capacity` doubles; out: y of the points, m */
  size_t capacity; /* in: how many points fit (at least 1000) */
  size_t count;    /* out: how many points were written (0 when the call starts) */
  /* out, on failure: why, a NUL-terminated text that stays valid until the next call with
   * this handle (a string literal, or a buffer in the handle). NULL when the call starts. */
  const char* error;
} overtake_path;

/* A planner instance, defined by the plugin (`struct overtake_plugin_handle { ... };`, or
 * cast a pointer of your own type). */
typedef struct overtake_plugin_handle overtake_plugin_handle;

/* Returns OVERTAKE_PLUGIN_ABI_VERSION (as compiled into the plugin). */
OVERTAKE_PLUGIN_EXPORT int overtake_plugin_abi_version(void);

/* The plugin's name and summary; the pointer and its strings stay valid while the library is
 * loaded. */
OVERTAKE_PLUGIN_EXPORT const overtake_plugin_info_t* overtake_plugin_info(void);

/* A new planner instance for one run. On failure: returns NULL and, when `error` is not
 * NULL, may set *error to a static NUL-terminated text saying why. */
OVERTAKE_PLUGIN_EXPORT overtake_plugin_handle* overtake_plugin_create(
    const overtake_plugin_setup* setup, const char** error);

/* Plans one cycle: reads `in`, writes at most out->capacity points into out->next_x and
 * out->next_y and sets out->count. Returns 0 on success; nonzero (and, best, out->error)
 * when it cannot plan, which ends the run as planner_failed. Every point must be finite. */
OVERTAKE_PLUGIN_EXPORT int overtake_plugin_plan(overtake_plugin_handle* handle,
                                                const overtake_telemetry* in, overtake_path* out);

/* Frees a handle made by overtake_plugin_create. Called once per handle. */
OVERTAKE_PLUGIN_EXPORT void overtake_plugin_destroy(overtake_plugin_handle* handle);

#endif /* OVERTAKE_PLANNER_PLUGIN_H */
