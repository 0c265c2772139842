/* C interface of the dynamics core: its variable tables (read by the FMU's model table and the model
 * description generator) and the core's lifetime, values, steps and equations, used by the probe
 * library (probe_api.h) and the core's tests. The FMU reaches the core through its model table instead
 * (model_core/src/simulation/fmu_model_table.cpp, the FMI faces' table over the core itself).
 * The core knows variables, physics and integration; the FMI layer knows the FMI state machine.
 * No function lets a C++ exception out: each returns GIMBAL_ERROR (with a logged reason) instead.
 * The core speaks no interface's language: its messages name no FMI function; a caller that serves
 * one prefixes it (the FMU's: fmi_log_from_model).
 * Every GimbalCore* argument must come from gimbal_core_create; NULL is refused. */
#ifndef GIMBAL_C_API_H
#define GIMBAL_C_API_H

#include <stddef.h>

#include "gimbal/gimbal_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct GimbalCore GimbalCore;

typedef enum { GIMBAL_PARAMETER = 0, GIMBAL_INPUT = 1, GIMBAL_OUTPUT = 2, GIMBAL_LOCAL = 3 } GimbalCausality;
typedef enum { GIMBAL_FIXED = 0, GIMBAL_TUNABLE = 1, GIMBAL_CONTINUOUS = 2 } GimbalVariability;
/* APPROX: the rotor angles and rates, settable like EXACT, which gear<j>.start may put in mesh instead. */
typedef enum {
    GIMBAL_INITIAL_NONE = 0,
    GIMBAL_INITIAL_EXACT = 1,
    GIMBAL_INITIAL_CALCULATED = 2,
    GIMBAL_INITIAL_APPROX = 3
} GimbalInitial;

/* category is one of the logCategories of modelDescription.xml. */
typedef void (*GimbalLogFunction)(void* context, GimbalStatus status, const char* category, const char* message);
/* Whether messages of a category would be logged: lets the core skip formatting them. */
typedef int (*GimbalLogEnabledFunction)(void* context, const char* category);

typedef struct GimbalVariableInfo {
    const char* name;
    GimbalCausality causality;
    GimbalVariability variability;
    GimbalInitial initial;
    const char* declared_type; /* an Integer's enumeration type (enumeration_types.def), or "" */
} GimbalVariableInfo;

typedef enum { GIMBAL_REAL = 0, GIMBAL_INTEGER = 1, GIMBAL_BOOLEAN = 2 } GimbalType;

/* FMI 3.0 value references: FMI 3.0 has one value-reference space for all types, and the core has one per
 * type (the .def tables). The FMI 3.0 layer and its model description add these offsets: Float64 at their
 * Real value reference, Int32 and Enumeration at GIMBAL_FMI3_INTEGER_BASE + theirs, Boolean at
 * GIMBAL_FMI3_BOOLEAN_BASE + theirs; time at GIMBAL_FMI3_TIME and the event indicators (FMI 3.0 makes them
 * variables) at GIMBAL_FMI3_FIRST_EVENT_INDICATOR + 0 .. GIMBAL_EVENT_INDICATORS - 1. */
enum {
    GIMBAL_FMI3_INTEGER_BASE = 1000,
    GIMBAL_FMI3_BOOLEAN_BASE = 2000,
    GIMBAL_FMI3_TIME = 3001,
    GIMBAL_FMI3_FIRST_EVENT_INDICATOR = 3002
};

/* Returns 0 when vr is not a variable of that type. */
int gimbal_variable_info(GimbalType type, unsigned vr, GimbalVariableInfo* info);
/* The index of the first of vr[0..count) that is not a variable of that type or cannot be set, or
 * count when all can. Settable before initialization (initialized = 0): inputs and variables with an
 * exact start value; after it: inputs and tunable parameters. One call per set of values: the
 * master's per-step input setting checks a value in a few instructions. */
size_t gimbal_first_unsettable(GimbalType type, const unsigned* vr, size_t count, int initialized);

GimbalCore* gimbal_core_create(GimbalLogFunction log, GimbalLogEnabledFunction enabled, void* log_context);
void gimbal_core_destroy(GimbalCore* core);
/* Back to the state right after creation: start values, no integrator. */
GimbalStatus gimbal_core_reset(GimbalCore* core);

GimbalStatus gimbal_core_set_real(GimbalCore* core, unsigned vr, double value);
/* Several at once, all or nothing: none is set if one is refused (an unknown value reference, a
 * value that is not finite). One call per fmi*SetReal / fmi3SetFloat64 of the host. */
GimbalStatus gimbal_core_set_reals(GimbalCore* core, const unsigned* vr, size_t count, const double* values);
GimbalStatus gimbal_core_get_real(GimbalCore* core, unsigned vr, double* value);
GimbalStatus gimbal_core_set_input_derivative(GimbalCore* core, unsigned vr, int order, double value);
GimbalStatus gimbal_core_set_integer(GimbalCore* core, unsigned vr, int value);
GimbalStatus gimbal_core_get_integer(GimbalCore* core, unsigned vr, int* value);
GimbalStatus gimbal_core_set_boolean(GimbalCore* core, unsigned vr, int value);
GimbalStatus gimbal_core_get_boolean(GimbalCore* core, unsigned vr, int* value);

/* fmi2SetupExperiment's tolerance (defined = 0: none). Used as solver.rtol unless solver.rtol is set. */
GimbalStatus gimbal_core_set_master_tolerance(GimbalCore* core, int defined, double tolerance);
/* Validates parameters and start values, and sets up the integrator at start_time. */
GimbalStatus gimbal_core_initialize(GimbalCore* core, double start_time);
/* Integrates from current_time to current_time + step_size with the inputs held. On failure the
 * state is rolled back to current_time and GIMBAL_DISCARD or GIMBAL_ERROR is returned. */
GimbalStatus gimbal_core_do_step(GimbalCore* core, double current_time, double step_size);
/* The same, but ending right after the first mode change when one comes before the end (a master
 * that allows an early return); *elapsed is how far the step went (step_size when it did not end
 * early), on the model's own clock: current_time + *elapsed is the host's time where it ended. */
GimbalStatus gimbal_core_do_step_until_mode_change(GimbalCore* core, double current_time, double step_size,
                                                   double* elapsed);
double gimbal_core_time(const GimbalCore* core);

/* Snapshots for fmi2GetFMUstate / fmi2SetFMUstate and their serialization: plain bytes of a fixed size. */
size_t gimbal_core_snapshot_size(void);
/* Saving ends the current integration segment, so that restoring it later replays bit for bit. */
GimbalStatus gimbal_core_save(GimbalCore* core, void* buffer);
/* Range-checks every field of a snapshot from an untrusted source; logs the reason of a refusal.
 * *initialized tells whether it holds an initialized instance. */
GimbalStatus gimbal_core_check_snapshot(GimbalCore* core, const void* buffer, int* initialized);
/* Checks the snapshot as above; a refused one leaves the instance as it was. */
GimbalStatus gimbal_core_restore(GimbalCore* core, const void* buffer);

/* ---- The continuous-time interface (FMI Model Exchange): the host integrates.
 * Chosen once per instance, right after creation. The states are always GIMBAL_CONTINUOUS_STATES
 * values in the order of gimbal_continuous_state_vr (a state the chosen fidelity does not integrate is
 * computed from the others, and what the host sets for it is not used); the indicators are
 * GIMBAL_EVENT_INDICATORS guards in a fixed order (an element the fidelity lacks gives constants).
 */
#define GIMBAL_CONTINUOUS_STATES 19
/* Each switching element's guards, summed from their one declaration (gimbal/switching_elements.def). */
enum {
    GIMBAL_EVENT_INDICATORS = 0
#define ELEMENT(identifier, instances, guards, element_switch, element_class) + (instances) * (guards)
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
};
GimbalStatus gimbal_core_use_continuous_time(GimbalCore* core);
/* The Real value references of state k and of its derivative; k in [0, GIMBAL_CONTINUOUS_STATES). */
unsigned gimbal_continuous_state_vr(int k);
unsigned gimbal_state_derivative_vr(int k);
/* After initialization only (GIMBAL_ERROR before), except the continuous states and the event
 * indicators: before, they are those of the start values (FMI's initialization mode). */
GimbalStatus gimbal_core_set_time(GimbalCore* core, double time);
GimbalStatus gimbal_core_set_continuous_states(GimbalCore* core, const double* states);
GimbalStatus gimbal_core_get_continuous_states(GimbalCore* core, double* states);
GimbalStatus gimbal_core_get_nominal_states(GimbalCore* core, double* nominals);
GimbalStatus gimbal_core_get_derivatives(GimbalCore* core, double* derivatives);
GimbalStatus gimbal_core_get_event_indicators(GimbalCore* core, double* indicators);
typedef struct GimbalDiscreteUpdate {
    int states_changed;    /* a transition moved the continuous states (projection onto a stop or limit) */
    int next_time_defined; /* the chattering guard holds the modes until next_time */
    double next_time;
    int mode_changes;
} GimbalDiscreteUpdate;
/* Decides the modes at the current point: where an indicator crossed zero since the last decision,
 * or an input jumped. A repeated call at the same point changes nothing. */
GimbalStatus gimbal_core_update_discrete_states(GimbalCore* core, GimbalDiscreteUpdate* update);
/* result = d(unknowns)/d(knowns) . seed at the current point, within the modes in force (a central
 * difference along the seed). Unknowns: state derivatives or outputs; knowns: states or inputs (Real
 * value references; anything else is refused with the reason). */
GimbalStatus gimbal_core_directional_derivative(GimbalCore* core, const unsigned* unknowns, size_t unknown_count,
                                                const unsigned* knowns, size_t known_count, const double* seed,
                                                double* result);

/* The continuous model linearized at the instance's current time and state, with its inputs as last
 * set, within the modes in force there (docs/linearization.md). Not exported by the FMU (it exports
 * only fmi2*): libgimbal_probe.so offers it to analysis tools. Matrices are row-major with the maximal
 * sizes as leading dimensions; only state_count rows / columns of the state dimension are used. */
#define GIMBAL_LINEAR_MAX_STATES 14 /* the 12 of the full model and the two current amplifiers' integrators */
#define GIMBAL_LINEAR_INPUTS 17
#define GIMBAL_LINEAR_OUTPUTS 17
typedef struct GimbalLinearModel {
    int state_count;
    unsigned state_vr[GIMBAL_LINEAR_MAX_STATES]; /* the Real output that carries each state */
    unsigned input_vr[GIMBAL_LINEAR_INPUTS];
    unsigned output_vr[GIMBAL_LINEAR_OUTPUTS];
    double A[GIMBAL_LINEAR_MAX_STATES][GIMBAL_LINEAR_MAX_STATES];
    double B[GIMBAL_LINEAR_MAX_STATES][GIMBAL_LINEAR_INPUTS];
    double C[GIMBAL_LINEAR_OUTPUTS][GIMBAL_LINEAR_MAX_STATES];
    double D[GIMBAL_LINEAR_OUTPUTS][GIMBAL_LINEAR_INPUTS];
    /* The modes the model holds in: gear contact -1/0/+1, current limiter -1/0/+1, voltage clamp
     * -1/0/+1, friction per body q-order: 0 none, 1 slipping +, 2 slipping -, 3 stuck (held),
     * 4 at the break-away torque +, 5 at the break-away torque -; the elevation end stop -1/0/+1
     * (resting on beta_min, free, resting on beta_max: at rest the model holds beta there). */
    int gear_contact[2];
    int motor_limited[2];
    int voltage_clamped[2];
    int friction[4];
    int elevation_stop;
    double time;
    /* Current drive: the amplifier's output -1 held at -U_L, 0 free, +1 held at +U_L (0 in voltage drive).
     * A current-driven motor's B and D column is its current command's (input_vr says i_R<j>_cmd). */
    int amplifier_saturated[2];
} GimbalLinearModel;

/* Refused (GIMBAL_ERROR) before initialization. */
GimbalStatus gimbal_core_linearize(GimbalCore* core, GimbalLinearModel* model);

#ifdef __cplusplus
}
#endif
#endif
