/* The external world's channel (docs/external-worlds.md): the shared memory through which
 * another process, in any language, renders the virtual world of an [external] scene at its
 * own rate. The environment is an admittance (22): the world reads the handle's state and
 * the coupling's force, and writes where its tool is.
 *
 * The daemon creates the channel per instance beside its control socket (SOCKET.sock ->
 * SOCKET.world, e.g. /run/hapticd/sim.world), mode 0660 in the socket's group (hapticd), and
 * removes it on every exit; a channel left by a daemon that died is replaced at the next start.
 * One mapping of HAPTICD_WORLD_SIZE bytes; all numbers little-endian, at the offsets pinned
 * below (the Python client, python/hapticd/external.py, reads them with struct).
 *
 * Two blocks, one writer each, each a sequence lock: the writer makes `sequence` odd, writes
 * the block, then makes it even again (one higher); a reader copies the block between two reads
 * of an even, equal `sequence`, and tries again otherwise. The servo tick never waits for the
 * world's block: a copy that raced a write is taken at a later tick. Only in lockstep
 * (lockstep_every > 0) does the tick wait, every lockstep_every steps, for the world's answer.
 *
 * Units SI. Every force is the force ON the tool, in newtons; the coupling's force on the tool
 * is k_c (x_d - x_e) + b_c (v_d - v_e) and the handle feels its negative. Vectors have 3
 * components; those past the scene's axes are 0.
 *
 * HAPTICD_WORLD_VERSION changes whenever a field below changes place or meaning.
 */
#ifndef HAPTICD_ENV_EXTERNAL_WORLD_H
#define HAPTICD_ENV_EXTERNAL_WORLD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HAPTICD_WORLD_MAGIC "hapticdW" /* 8 bytes, no NUL */
#define HAPTICD_WORLD_VERSION 1u
#define HAPTICD_WORLD_SIZE 4096u

/* hapticd_world_tick.state */
#define HAPTICD_WORLD_WAITING 0u /* no update from a world yet: the tool follows the handle */
#define HAPTICD_WORLD_LIVE 1u    /* updates come within stale_after_s */
#define HAPTICD_WORLD_STALE 2u   /* none for stale_after_s: the tool holds, the force ramps to 0 */

/* At offset 0, written once when the daemon creates the channel, the magic last: a header
 * without it is not written yet. `closed` is set when the daemon lets go. */
typedef struct hapticd_world_header {
    char magic[8];           /* 0: HAPTICD_WORLD_MAGIC */
    uint32_t version;        /* 8: HAPTICD_WORLD_VERSION */
    uint32_t size;           /* 12: HAPTICD_WORLD_SIZE */
    uint32_t axes;           /* 16: the scene's axes, 1..3 */
    uint32_t lockstep_every; /* 20: 0 free-running; N: the tick waits for the world every N */
    double rate_hz;          /* 24: the servo's rate */
    double stale_after_s;    /* 32: no update for this long is stale (s of the servo's time) */
    int32_t daemon_pid;      /* 40: the daemon that created it */
    uint32_t closed;         /* 44: 1 once the daemon has let go of it: connect again */
    uint8_t reserved[16];    /* 48 */
} hapticd_world_header;

/* At offset 64: the daemon's block, written at the end of every step of the environment, and in
 * lockstep once more before the tool of a step that asks is chosen: that block has the step's
 * handle, and the tool and force of the step before. */
typedef struct hapticd_world_tick {
    uint64_t sequence;           /* 64 */
    uint64_t step;               /* 72: the environment's steps since the channel began, from 1 */
    uint64_t answer_for;         /* 80: lockstep: the step that asks for an answer, until one
                                    comes (a step that timed out asks on, without waiting) */
    double time_s;               /* 88: the servo's time at this step (the sum of its intervals) */
    double period_s;             /* 96: this step's interval T */
    double stiffness_n_per_m;    /* 104: k_c in force */
    double damping_n_s_per_m;    /* 112: b_c in force */
    double handle_position_m[3]; /* 120: x_d */
    double handle_velocity_mps[3]; /* 144: v_d, the backward difference */
    double tool_position_m[3];     /* 168: x_e as rendered at the step (after the controller) */
    double coupling_force_n[3];    /* 192: the coupling's force on the tool at the step */
    double energy_removed_j;       /* 216: what the passivity controller has taken, since start */
    uint32_t state;                /* 224: HAPTICD_WORLD_WAITING, _LIVE or _STALE */
    uint32_t reserved;             /* 228 */
    uint64_t update_in_force;      /* 232: the world's update the step rendered (0: none) */
    uint8_t reserved_end[16];      /* 240 */
} hapticd_world_tick;

/* At offset 256: the world's block, written whenever it has a new tool state. */
typedef struct hapticd_world_update {
    uint64_t sequence;           /* 256 */
    uint64_t update;             /* 264: the world's count of its updates, from 1 */
    uint64_t answers;            /* 272: lockstep: the step (answer_for) this answers; else 0 */
    double world_time_s;         /* 280: the world's own clock, for the record (NaN: none) */
    double tool_position_m[3];   /* 288: x_e, where the world's tool is */
    double tool_velocity_mps[3]; /* 312: its velocity, for extrapolation (NaN: not given) */
    uint8_t reserved_end[48];    /* 336 */
} hapticd_world_update;

#define HAPTICD_WORLD_TICK_OFFSET 64u
#define HAPTICD_WORLD_UPDATE_OFFSET 256u

#ifdef __cplusplus
}
static_assert(sizeof(hapticd_world_header) == HAPTICD_WORLD_TICK_OFFSET);
static_assert(sizeof(hapticd_world_tick) ==
              HAPTICD_WORLD_UPDATE_OFFSET - HAPTICD_WORLD_TICK_OFFSET);
static_assert(sizeof(hapticd_world_update) == 128);
static_assert(offsetof(hapticd_world_header, closed) == 44);
static_assert(offsetof(hapticd_world_tick, handle_position_m) == 120 - 64);
static_assert(offsetof(hapticd_world_tick, energy_removed_j) == 216 - 64);
static_assert(offsetof(hapticd_world_tick, update_in_force) == 232 - 64);
static_assert(offsetof(hapticd_world_update, tool_position_m) == 288 - 256);
static_assert(offsetof(hapticd_world_update, tool_velocity_mps) == 312 - 256);
#endif

#endif /* HAPTICD_ENV_EXTERNAL_WORLD_H */
