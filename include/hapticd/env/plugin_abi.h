/* The environment plugin ABI (docs/environment-plugins.md): a lab's own virtual world as a
 * shared object that hapticd loads by name from a scene file ([plugin] name = "..."), in
 * either causality of Adams & Hannaford:
 *
 *   impedance (17): the servo solves the coupling (16) in series with the world for the
 *     massless tool x_e, asking evaluate() for the force on the tool and its linearisation
 *     at trial states (several times a tick), then commit()s the solution once a tick;
 *   admittance (22): step() gets the handle's state and the coupling's gains and returns the
 *     tool's position x_e (a proxy, a virtual mass integrated implicitly...).
 *
 * Plain C, so that a world may be written in C, C++, Rust or anything with a C FFI, built by
 * any compiler. Find it with CMake: find_package(hapticd) and hapticd_add_environment_plugin()
 * (examples/environment-plugin/).
 *
 * Units SI. Every force is the force ON the tool, in newtons, along +x/+y/+z; the coupling's
 * force on the tool is k_c (x_d - x_e) + b_c (v_d - v_e) and the handle feels its negative.
 * Vectors have 3 components; those past the scene's axes are 0 and must be left at 0.
 *
 * Real time: reset(), evaluate(), commit() and step() run inside the servo tick. They must not
 * allocate, lock, block, log or throw, and must return within the scene's [plugin] max_call_us
 * of CPU time. create() and destroy() run outside it, on another thread.
 *
 * Faults: a call that returns non-zero, writes a value that is not finite, throws (a C++
 * plugin's exception is caught at the boundary) or takes longer than its time is a fault:
 * the force goes to zero at once and stays there (latched: fault "environment", or
 * "non_finite" for a NaN), the world is not called again until hapticctl reset, and the
 * reason is in the journal, the status and the summary. hapticd never crashes on it.
 *
 * Versioning: abi_version is the first member of the descriptor in every version, and the
 * loader reads it before anything else; a plugin of another version is refused by name.
 * HAPTICD_ENVIRONMENT_ABI_VERSION changes whenever a type below changes layout or meaning.
 */
#ifndef HAPTICD_ENV_PLUGIN_ABI_H
#define HAPTICD_ENV_PLUGIN_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HAPTICD_ENVIRONMENT_ABI_VERSION 1u
#define HAPTICD_ENVIRONMENT_PLUGIN_ENTRY_SYMBOL "hapticd_environment_plugin_entry"

/* hapticd_environment_plugin.causality */
#define HAPTICD_ENV_IMPEDANCE 0u
#define HAPTICD_ENV_ADMITTANCE 1u

/* What the scene gives create(). */
typedef struct hapticd_env_setup {
    uint32_t axes;          /* the scene's axes, 1..3 */
    double rate_hz;         /* the servo's rate; the period is 1 / rate_hz */
    const char* settings;   /* the scene's [plugin.settings] table as TOML text ("" if none) */
    const char* scene_file; /* the scene file's path, for messages ("" for none) */
} hapticd_env_setup;

/* evaluate()'s answer: f_env on the tool at the trial state, and its linearisation. */
typedef struct hapticd_env_penalty {
    double force_n[3];
    double stiffness_n_per_m[9]; /* -df/dx_e, row-major: [row * 3 + column] */
    double damping_n_s_per_m[9]; /* -df/dv_e, row-major */
} hapticd_env_penalty;

/* step()'s view of the coupling (16) in this tick. */
typedef struct hapticd_env_coupling {
    double stiffness_n_per_m; /* k_c */
    double damping_n_s_per_m; /* b_c */
    double period_s;          /* T */
} hapticd_env_coupling;

typedef struct hapticd_environment_plugin {
    uint32_t abi_version;    /* HAPTICD_ENVIRONMENT_ABI_VERSION: first, in every version */
    uint32_t causality;      /* HAPTICD_ENV_IMPEDANCE or HAPTICD_ENV_ADMITTANCE */
    const char* name;        /* e.g. "spring-wall" */
    const char* description; /* one line */

    /* A new world for `setup`, or NULL with a NUL-terminated message in `message` (at most
     * `capacity` bytes: name the file, the key, the value and what is allowed). */
    void* (*create)(const hapticd_env_setup* setup, char* message, size_t capacity);
    void (*destroy)(void* world);

    /* Forget all state; the tool starts at `position_m` (impedance), or at the constrained
     * point nearest it (admittance). 0: done. */
    int32_t (*reset)(void* world, const double position_m[3]);

    /* Impedance worlds (NULL in an admittance plugin). */
    int32_t (*evaluate)(const void* world, const double tool_position_m[3],
                        const double tool_velocity_mps[3], hapticd_env_penalty* out);
    int32_t (*commit)(void* world, const double tool_position_m[3],
                      const double tool_velocity_mps[3]);

    /* Admittance worlds (NULL in an impedance plugin): the tool's position for the handle at
     * `device_position_m` moving at `device_velocity_mps` (backward difference). */
    int32_t (*step)(void* world, const double device_position_m[3],
                    const double device_velocity_mps[3], const hapticd_env_coupling* coupling,
                    double tool_position_m[3]);
} hapticd_environment_plugin;

/* The one symbol a plugin exports (visibility default). */
const hapticd_environment_plugin* hapticd_environment_plugin_entry(void);

#ifdef __cplusplus
}
#endif

#endif /* HAPTICD_ENV_PLUGIN_ABI_H */
