/*
 * overtake planner plugins: the C ABI, version 2.1.
 *
 * A plugin is a shared library that defines the five functions declared at the end of this
 * header. `overtake drive|bench|serve --policy-lib [NAME=]PATH` loads it (dlopen), checks
 * the version overtake_plugin_abi_version() reports and that every function is there, and
 * then runs it in-process like a built-in policy: one handle per run (drive, each bench run,
 * each `serve` connection), one call of overtake_plugin_plan per telemetry message.
 *
 * What the planner sees is what the original Udacity Term 3 simulator sends over its
 * websocket, field for field and in the same units (metres, DEGREES for yaw, MPH for the
 * ego's speed, m/s for the other cars' velocities), rounded as the original's wire rounds
 * numbers (32-bit floats, 7 significant digits). A planner written for the original ports
 * over by replacing its JSON parsing with these structs.
 *
 * Pure C (C99 and later) and C++. Only fixed-size types and pointers cross the boundary.
 *
 * ---- Versions and how the ABI grows ----
 *
 * The version is MAJOR.MINOR. overtake loads a plugin built for its own major version and a
 * minor version up to its own, so a plugin built against an older 2.x header loads in every
 * later 2.y overtake without being rebuilt; it refuses another major version and a newer
 * minor, naming both versions.
 *
 * Within a major version the ABI only ever grows by appending: a new field goes at the end of
 * its struct (never inserted, removed, reordered or retyped), marked with the minor version
 * that added it, and the minor version goes up. Each struct overtake fills begins with
 * `struct_size`, which overtake sets to sizeof(the struct) as it was compiled. So:
 * - a plugin built against an older minor reads the prefix it knows and never sees the rest;
 * - a plugin built against this header that reports an OLDER minor than this header's (to
 *   load in older overtakes too, see OVERTAKE_PLUGIN_MAKE_VERSION) must check struct_size
 *   before it reads a field appended after the minor it reports:
 *   OVERTAKE_PLUGIN_HAS_FIELD(in, overtake_telemetry, speed_mps);
 * - overtake_waypoint and the rows of sensor_fusion are array elements, whose size cannot
 *   grow: they stay as they are for all of version 2 (more per-element data would come as a
 *   new array appended to the struct that holds them);
 * - structs the plugin fills (overtake_plugin_info, the "out" fields of overtake_path) grow
 *   the same way; overtake reads an appended field only from a plugin whose reported minor
 *   has it, and sets the appended "out" fields of overtake_path to a neutral value before the
 *   call, so a plugin that does not know them leaves them be;
 * - a later minor may add functions; they will be optional (looked up by name, a plugin
 *   without them works as before).
 * Why a size field in each struct rather than one entry point returning a table of functions:
 * what grows is the data (telemetry fields first), and a size per struct lets each struct grow
 * on its own and tells the plugin exactly which fields this overtake has; functions are
 * already found by name, so a new optional function needs no table to be detected.
 *
 * ---- Threads ----
 *
 * overtake calls a plugin's functions from several threads: a bench runs several runs at
 * once, so different handles may be used at the same time from different threads. Keep every
 * piece of state in the handle (no mutable globals). One handle is only ever used by one
 * thread at a time.
 *
 * A plugin may start threads of its own (a worker pool, a background search). Such a thread
 * must not call into overtake (it has no functions to call) nor touch anything overtake passed
 * (setup, telemetry and path live only during the call that receives them). Every thread a
 * handle started must be stopped and joined in overtake_plugin_destroy of that handle before
 * it returns; a thread shared by several handles, when the last of them is destroyed. overtake
 * loads plugins with RTLD_NODELETE, so the library's code stays mapped after overtake is done
 * with it: a thread that is just finishing when destroy returns, or a plan call that never
 * returns and is abandoned, does not crash the process.
 *
 * ---- Exceptions ----
 *
 * Do not let a C++ exception leave these functions. (overtake catches one that does and ends
 * the run as planner_failed, but unwinding through a C interface is not something to rely
 * on.) Report failures with a NULL handle or a nonzero status and an error message.
 *
 * ---- From version 1 ----
 *
 * overtake_plugin_info_t is now overtake_plugin_info and is returned by
 * overtake_plugin_get_info(); overtake_plugin_create writes its reason into a buffer of the
 * caller; setup, telemetry and path begin with struct_size (overtake sets it); empty arrays
 * may be NULL. overtake refuses plugins of version 1 and says so.
 */
#ifndef OVERTAKE_PLANNER_PLUGIN_H
#define OVERTAKE_PLANNER_PLUGIN_H

#include <stddef.h>

/* The version of this header. A major version changes when something built against the
 * previous one cannot work any more; a minor version when something is appended. */
#define OVERTAKE_PLUGIN_ABI_MAJOR 2
#define OVERTAKE_PLUGIN_ABI_MINOR 1

/* The single number overtake_plugin_abi_version() returns: major * 1000 + minor (2.1 is
 * 2001). One int, not two out-parameters, because version 1 had the same function returning
 * 1: a version-1 plugin is still read correctly, and refused by name. */
#define OVERTAKE_PLUGIN_MAKE_VERSION(major, minor) ((major)*1000 + (minor))
#define OVERTAKE_PLUGIN_ABI_VERSION \
  OVERTAKE_PLUGIN_MAKE_VERSION(OVERTAKE_PLUGIN_ABI_MAJOR, OVERTAKE_PLUGIN_ABI_MINOR)

/* Whether the struct at `ptr` (a pointer to `type`, which begins with struct_size) has
 * `field`: true when the struct overtake filled reaches past that field's end. */
#define OVERTAKE_PLUGIN_HAS_FIELD(ptr, type, field) \
  ((ptr)->struct_size >= offsetof(type, field) + sizeof((ptr)->field))

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

/* How many bytes the error buffer of overtake_plugin_create holds at least. */
#define OVERTAKE_PLUGIN_MIN_ERROR_SIZE 256

/* The plugin's name and a one-line description; filled by the plugin. */
typedef struct overtake_plugin_info {
  /* Letters, digits, '_', '-', '.': the planner's name in reports and bench tables (unless
   * the user names it with NAME=). Not NULL, not empty. */
  const char* name;
  /* One line saying what the planner does (may be NULL or empty). */
  const char* summary;
} overtake_plugin_info;

/* One line of the map file (highway_map.csv in the original): the road's divider (the
 * left edge of the leftmost lane) at distance s along the road. An array element: its
 * layout is fixed for all of version 2. */
typedef struct overtake_waypoint {
  double x;  /* m, map axes */
  double y;  /* m */
  double s;  /* m along the road from the map's start */
  double dx; /* unit normal, pointing away from the divider (towards increasing d) */
  double dy;
} overtake_waypoint;

/* What a plugin is given once per handle; filled by overtake. Everything it points to is
 * valid only during the call of overtake_plugin_create: copy what you keep. */
typedef struct overtake_plugin_setup {
  /* bytes: sizeof(overtake_plugin_setup) as overtake was compiled (see "Versions"). */
  size_t struct_size;
  /* The map's waypoints, in the map's order (181 for the original's highway_map.csv; never
   * empty). */
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
  /* Parameters for this plugin as a JSON object of numbers by name, e.g.
   * {"cruise_mps":21.5}, or NULL when none: `overtake tune` passes each trial's values here
   * (its --param names); drive and bench pass NULL. A plugin reads the names it knows and
   * keeps its defaults for the rest. */
  const char* config_json;
} overtake_plugin_setup;

/* One telemetry message, as the original sends it (its keys, its units); filled by overtake.
 * Everything it points to is valid only during the call of overtake_plugin_plan. */
typedef struct overtake_telemetry {
  /* bytes: sizeof(overtake_telemetry) as overtake was compiled (see "Versions"). */
  size_t struct_size;
  double x;     /* m: the ego's position, map axes */
  double y;     /* m */
  double s;     /* m: Frenet s of the ego (measured on the straight chords between waypoints,
                   as the original does) */
  double d;     /* m: Frenet d of the ego, from the divider (lane i: lane_width*i .. *(i+1)) */
  double yaw;   /* DEGREES, counter-clockwise from +x, in [0, 360) */
  double speed; /* MPH (the ego's distance in the last step over the step time) */
  /* The points of the last path this planner sent that the car has not driven yet, in
   * driving order (x[i], y[i]), m. Empty (count 0) at the start; when empty, both pointers
   * may be NULL (read them only for i < previous_path_count). */
  const double* previous_path_x;
  const double* previous_path_y;
  size_t previous_path_count;
  /* m: Frenet s and d of the last point of previous_path; both 0 when it is empty. */
  double end_path_s;
  double end_path_d;
  /* The other cars, one row each: [id, x, y, vx, vy, s, d] (see OVERTAKE_SF_*): id (a whole
   * number), position in m, velocity in M/S in map axes (not mph), Frenet s and d in m.
   * With no cars (count 0) the pointer may be NULL. */
  const double (*sensor_fusion)[OVERTAKE_SF_COLUMNS];
  size_t sensor_fusion_count;
  /* Since 2.1. m/s: the ego's speed in SI units (`speed` is the same speed converted to mph
   * and rounded as the original's wire does), so a planner need not convert it back. */
  double speed_mps;
} overtake_telemetry;

/* The path a planner answers: the points the ego drives through, one per step_time, in
 * driving order (the original's next_x, next_y). overtake provides the buffers: write into
 * them (replacing the pointers fails the cycle). Fields marked "in" are overtake's: do not
 * change them. */
typedef struct overtake_path {
  /* in: bytes, sizeof(overtake_path) as overtake was compiled (see "Versions"); writing over
   * it fails the cycle. */
  size_t struct_size;
  double* next_x;  /* in: a buffer of `capacity` doubles; out: x of the points, m */
  double* next_y;  /* in: a buffer of `capacity` doubles; out: y of the points, m */
  size_t capacity; /* in: how many points fit (at least 1000) */
  size_t count;    /* out: how many points were written (0 when the call starts) */
  /* out, on failure: why, a NUL-terminated text that stays valid until the next call with
   * this handle (a string literal, or a buffer in the handle). NULL when the call starts;
   * left NULL, the failure is reported without a reason. */
  const char* error;
} overtake_path;

/* A planner instance, defined by the plugin (`struct overtake_plugin_handle { ... };`, or
 * cast a pointer of your own type). */
typedef struct overtake_plugin_handle overtake_plugin_handle;

/* Returns the version the plugin was built for: OVERTAKE_PLUGIN_ABI_VERSION as compiled into
 * it (or an older 2.x made with OVERTAKE_PLUGIN_MAKE_VERSION, see "Versions"). Called first,
 * before any other function is looked up. */
OVERTAKE_PLUGIN_EXPORT int overtake_plugin_abi_version(void);

/* The plugin's name and summary; the pointer and its strings stay valid while the library is
 * loaded. */
OVERTAKE_PLUGIN_EXPORT const overtake_plugin_info* overtake_plugin_get_info(void);

/* A new planner instance for one run. On failure: returns NULL and may write why into
 * `error`, a buffer of `error_size` bytes (at least OVERTAKE_PLUGIN_MIN_ERROR_SIZE) that
 * holds an empty text when the call starts: a NUL-terminated text that fits, e.g.
 * snprintf(error, error_size, ...). overtake never passes NULL; a message that fills the
 * buffer without its NUL is cut to error_size - 1 characters. */
OVERTAKE_PLUGIN_EXPORT overtake_plugin_handle* overtake_plugin_create(
    const overtake_plugin_setup* setup, char* error, size_t error_size);

/* Plans one cycle: reads `in`, writes at most out->capacity points into out->next_x and
 * out->next_y and sets out->count. Returns 0 on success; nonzero (and, best, out->error)
 * when it cannot plan, which ends the run as planner_failed. Every point must be finite. */
OVERTAKE_PLUGIN_EXPORT int overtake_plugin_plan(overtake_plugin_handle* handle,
                                                const overtake_telemetry* in, overtake_path* out);

/* Frees a handle made by overtake_plugin_create, after stopping the threads it started (see
 * "Threads"). Called once per handle. */
OVERTAKE_PLUGIN_EXPORT void overtake_plugin_destroy(overtake_plugin_handle* handle);

#endif /* OVERTAKE_PLANNER_PLUGIN_H */
