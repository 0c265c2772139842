/* Analysis entries into the dynamics core, built as libgimbal_probe.so beside the FMU (never part of
 * it: the FMU exports only fmi2*).
 * - The linearization of the continuous model (docs/linearization.md), which `gimbal2axis linearize`
 *   and gimbal2axis.analysis.linearization use.
 * - J(q) and f(q, qd, base motion) of the rigid-body equations, which the tests compare with an
 *   independent symbolic derivation. */
#ifndef GIMBAL_PROBE_API_H
#define GIMBAL_PROBE_API_H

#include <stddef.h>

#include "gimbal/gimbal_c_api.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bodies are ordered as the generalized coordinates q = [alpha, alpha_m, beta, beta_m]:
 * index 0 = body 1 (azimuth housing), 1 = rotor R1, 2 = body 2 (elevation payload), 3 = rotor R2. */
typedef struct GimbalProbeRigidBodyInput {
    double mass[4];            /* kg */
    double inertia[4][6];      /* I_xx, I_yy, I_zz, I_xy, I_xz, I_yz about the centre of mass, own frame, kg.m2 */
    double com[4][3];          /* d_bc (frame 1), d_be (frame R1), d_bd (frame 2), d_bf (frame R2), m */
    double d_ab[3];            /* frame 0, m */
    double g;                  /* m/s2 */
    double q[4];               /* rad */
    double qd[4];              /* rad/s */
    double attitude[3];        /* delta (pitch), psi (yaw), gamma (roll), rad */
    double attitude_rate[3];   /* rad/s */
    double attitude_accel[3];  /* rad/s2 */
    double v_a[3];             /* velocity of point a, G coordinates, m/s */
    double a_a[3];             /* acceleration of point a, G coordinates, m/s2 */
} GimbalProbeRigidBodyInput;

/* Writes J (row-major 4x4) and f (4) such that J qdd = Xi + f. Returns 0 on success. */
int gimbal_probe_mass_matrix_and_bias(const GimbalProbeRigidBodyInput* input, double J_row_major[16], double f[4]);

/* The FMU's variables, by type (GimbalType) and value reference: 1 and the name, or 0 past the last. */
int gimbal_probe_variable(int type, unsigned vr, const char** name, int* causality);

/* Size of the core's part of a serialized FMU state (fmi2SerializeFMUstate gives a 128-byte header,
 * then these bytes). */
size_t gimbal_probe_snapshot_size(void);

/* The dimensions of GimbalLinearModel (gimbal_c_api.h) and its size in bytes, so that a binding builds
 * its view of the struct from the library instead of copying the numbers. */
void gimbal_probe_linear_model_layout(int* max_states, int* inputs, int* outputs, size_t* size);

typedef struct GimbalProbeSetting {
    int type; /* GimbalType */
    unsigned vr;
    double value; /* an Integer or Boolean value is converted exactly */
} GimbalProbeSetting;

/* Linearizes at an operating point. Without a snapshot: a fresh instance gets the settings
 * (parameters, start values of the states, inputs) and is initialized at time 0. With one: the
 * instance is restored from it (parameters, state, modes and inputs of a running simulation) and
 * then gets the settings, which may only be inputs. Returns 0, or 1 with the reason in message. */
int gimbal_probe_linearize(const GimbalProbeSetting* settings, size_t setting_count, const void* snapshot,
                           size_t snapshot_size, GimbalLinearModel* model, char* message, size_t message_size);

#ifdef __cplusplus
}
#endif
#endif
