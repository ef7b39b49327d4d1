/* An environment plugin (include/hapticd/env/plugin_abi.h, docs/environment-plugins.md): a
 * wall on the first axis, a spring and a damper that push the tool back into free space, as a
 * penalty (impedance) world: what hapticd's own [[wall]] with normal [normal] renders, force
 * for force. In plain C, to show that nothing of C++
 * crosses the ABI.
 *
 * Its scene (spring-wall.toml):
 *   [scene]
 *   name = "my wall"
 *   axes = 1
 *   [plugin]
 *   name = "spring-wall"          # libhapticd-env-spring-wall.so on HAPTICD_PLUGIN_PATH
 *   [plugin.settings]
 *   stiffness = 2000.0            # N/m, > 0
 *   damping = 1.0                 # N s/m, >= 0
 *   position = -0.005             # m, the wall's plane on the first axis
 *   normal = 1.0                  # the free side: +1 (x > position) or -1 (x < position)
 *
 * The settings come as TOML text; a world in C++ would hand it to toml++. This one reads
 * its three numbers with sscanf, and refuses any other key.
 */
#include <hapticd/env/plugin_abi.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct wall {
    double stiffness_n_per_m;
    double damping_n_s_per_m;
    double position_m;
    double normal; /* +1 or -1: the direction of free space */
} wall;

/* Reads `key = number` lines of the settings; 0 on success, else writes why into `message`. */
static int read_settings(const char* settings, const char* scene_file, wall* w, char* message,
                         size_t capacity) {
    w->stiffness_n_per_m = 1000.0;
    w->damping_n_s_per_m = 0.0;
    w->position_m = 0.0;
    w->normal = 1.0;
    const char* line = settings;
    while (line != NULL && *line != '\0') {
        char key[64];
        double value = 0.0;
        const char* end = strchr(line, '\n');
        const size_t length = end != NULL ? (size_t)(end - line) : strlen(line);
        if (sscanf(line, " %63[a-z_] = %lf", key, &value) == 2) {
            if (strcmp(key, "stiffness") == 0 && value > 0.0 && value <= 1e7) {
                w->stiffness_n_per_m = value;
            } else if (strcmp(key, "damping") == 0 && value >= 0.0 && value <= 1e5) {
                w->damping_n_s_per_m = value;
            } else if (strcmp(key, "position") == 0 && fabs(value) <= 1.0) {
                w->position_m = value;
            } else if (strcmp(key, "normal") == 0 && fabs(value) == 1.0) {
                w->normal = value;
            } else {
                snprintf(message, capacity,
                         "%s: [plugin.settings] %s = %g: allowed stiffness (> 0 and <= 1e7 "
                         "N/m), damping (>= 0 and <= 1e5 N s/m), position (within 1 m), "
                         "normal (1 or -1)",
                         scene_file, key, value);
                return -1;
            }
        } else if (strspn(line, " \t\r") < length) {
            snprintf(message, capacity, "%s: [plugin.settings]: a line that is not key = number",
                     scene_file);
            return -1;
        }
        line = end != NULL ? end + 1 : NULL;
    }
    return 0;
}

static void* create(const hapticd_env_setup* setup, char* message, size_t capacity) {
    wall* w = malloc(sizeof *w); /* create() runs outside the tick: it may allocate */
    if (w == NULL) {
        snprintf(message, capacity, "out of memory");
        return NULL;
    }
    if (read_settings(setup->settings, setup->scene_file, w, message, capacity) != 0) {
        free(w);
        return NULL;
    }
    return w;
}

static void destroy(void* world) { free(world); }

static int32_t reset(void* world, const double position_m[3]) {
    (void)world;
    (void)position_m;
    return 0; /* no state */
}

/* The force on the tool past the wall, n (k depth - b n v) with depth = n (position - x),
 * into free space only: a wall that would pull lets go instead (as hapticd's own [[wall]],
 * penalty_objects.cpp). */
static int32_t evaluate(const void* world, const double x[3], const double v[3],
                        hapticd_env_penalty* out) {
    const wall* w = world;
    memset(out, 0, sizeof *out);
    const double depth_m = w->normal * (w->position_m - x[0]);
    if (depth_m <= 0.0) return 0;
    const double push_n =
        w->stiffness_n_per_m * depth_m - w->damping_n_s_per_m * (w->normal * v[0]);
    if (push_n <= 0.0) return 0;
    out->force_n[0] = push_n * w->normal;
    out->stiffness_n_per_m[0] = w->stiffness_n_per_m;
    out->damping_n_s_per_m[0] = w->damping_n_s_per_m;
    return 0;
}

static int32_t commit(void* world, const double x[3], const double v[3]) {
    (void)world;
    (void)x;
    (void)v;
    return 0;
}

__attribute__((visibility("default"))) const hapticd_environment_plugin*
hapticd_environment_plugin_entry(void) {
    static const hapticd_environment_plugin plugin = {
        .abi_version = HAPTICD_ENVIRONMENT_ABI_VERSION,
        .causality = HAPTICD_ENV_IMPEDANCE,
        .name = "spring-wall",
        .description = "a spring-damper wall on the first axis (examples/environment-plugin)",
        .create = create,
        .destroy = destroy,
        .reset = reset,
        .evaluate = evaluate,
        .commit = commit,
        .step = NULL,
    };
    return &plugin;
}
