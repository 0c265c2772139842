// The model's types: the constant model (parameters, fidelity, state layout), the discrete modes
// (one slot per switching element), the inputs over a step, and the dynamics at one instant. Below
// the switching elements (switching_elements/) and the dynamics that assemble them (gimbal_model.hpp).
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "gimbal/multibody/disturbance_torques.hpp"
#include "gimbal/multibody/drive_train.hpp"
#include "gimbal/multibody/rigid_body.hpp"

namespace gimbal {

// Layout of the full state vector (docs/physics.md section 3.3). Reduced fidelities drop entries: see StateLayout.
enum StateIndex : int {
    kAngles = 0,      // alpha, alpha_m, beta, beta_m
    kRates = 4,       // their time derivatives
    kCurrents = 8,    // i_R1, i_R2
    kBacklash = 10,   // theta_b1, theta_b2
    kStateSize = 12,
    kEnergyFlowCount = 5,  // electrical in, resistive, viscous, shaft damping, dry friction
    // The current amplifiers' integrators x_I (a current-commanded inductive motor only), after the energy
    // accumulators in the Model Exchange state vector (indices 17, 18); in the integrated state vector
    // they sit before the energy accumulators (StateLayout::amplifier_slot).
    kAmplifierStates = kStateSize + kEnergyFlowCount,
    kAmplifierIntegratorCount = 2,
    kMaxStateSize = kStateSize + kEnergyFlowCount + kAmplifierIntegratorCount
};

enum EnergyFlow : int { kElectricalIn = 0, kResistive, kViscous, kShaftDamping, kDryFriction };

// "Model only what a scene needs" (docs/physics.md section 6): each reduction removes states.
enum class GearModel : int { rigid = 0, compliant = 1, backlash = 2 };
// Where a compliant gear's rotor starts (gear<j>.start, docs/physics.md section 3.3): in mesh with its
// load unless a start value other than 0 was given, always in mesh, or at its start values as given.
enum class GearStart : int { in_mesh_unless_given = 0, in_mesh = 1, as_given = 2 };
enum class MotorModel : int { quasi_static = 0, inductive = 1 };
// What a motor's input commands (motor<j>.drive, docs/physics.md section 4.6): the armature voltage u_R<j>
// (default), or the armature current i_R<j>_cmd through the servo amplifier's current loop.
enum class DriveMode : int { voltage = 0, current = 1 };

struct Fidelity {
    GearModel gear[2] = {GearModel::backlash, GearModel::backlash};
    MotorModel motor[2] = {MotorModel::inductive, MotorModel::inductive};
    DriveMode drive[2] = {DriveMode::voltage, DriveMode::voltage};
    bool dry_friction = true;
    bool fixed_base = false;
};

// Rotor coordinate of axis j in q order (alpha_m, beta_m) and its load coordinate (alpha, beta).
constexpr int rotor_index(int axis) { return axis == 0 ? 1 : 3; }
constexpr int load_index(int axis) { return axis == 0 ? 0 : 2; }
// The axis end stops (switching_elements/axis_stop.hpp), one per AXIS_STOP row of
// gimbal/switching_elements.def, in its order: hard stops of one coordinate at lower and upper, Newton's
// impact law with the coefficient of restitution, rest on a stop below the rebound rate rest_rate. Off by
// default: no guard, no mode, no term in any sum.
constexpr int kAxisStopCount = 0
#define AXIS_STOP(element, coordinate, lower, upper, restitution, rest_rate, contact) +1
#define ELEMENT(identifier, instances, guards, element_switch, element_class)
#define MODE_OUTPUT(element, output, lowest, highest)
#include "gimbal/switching_elements.def"
#undef MODE_OUTPUT
#undef ELEMENT
#undef AXIS_STOP
    ;
struct AxisStopParameters {
    bool present = false;
    double lower = -1.5707963267948966;  // rad
    double upper = 1.5707963267948966;   // rad
    double restitution = 0.5;            // 1
    double rest_rate = 1e-3;             // rad/s
};

// Where each quantity lives in the integrated state vector; -1 when the fidelity removed it.
// Coordinates are "padded": a rigid axis's rotor keeps its index 0..3 in the equations of motion
// but has no state (q_m = N q_l).
struct StateLayout {
    int angle_slot[4];
    int rate_slot[4];
    int current_slot[2];
    int backlash_slot[2];
    int amplifier_slot[2];  // the amplifier's integrator x_I: a current-commanded inductive motor only
    int energy_slot;  // first of kEnergyFlowCount, or -1
    int size;
    bool canonical;   // every quantity present, in StateIndex order (full fidelity): no slot lookups

    static StateLayout from(const Fidelity& fidelity, bool energy_accounting);
    bool independent(int body) const { return angle_slot[body] >= 0; }
};

struct ModelParameters {
    MultibodyModel multibody;
    MotorParameters motor[2];
    AmplifierParameters amplifier[2];  // used by a current-commanded motor (fidelity.drive) only
    GearParameters gear[2];
    double viscous_friction[4] = {0, 0, 0, 0};  // per body, q order
    DryFrictionParameters dry_friction[4];      // per body, as given
    DisturbanceParameters disturbances;         // cable restraints and cogging; `active` set by finalize()
    AxisStopParameters axis_stop[kAxisStopCount];
    Fidelity fidelity;
    // Where the compliant gears' rotors start (gear<j>.start): used only by the start state.
    GearStart gear_start[2] = {GearStart::in_mesh_unless_given, GearStart::in_mesh_unless_given};
    bool energy_accounting = false;
    double relative_tolerance = 1e-6;
    double absolute_tolerance = 1e-8;
    long max_steps = 100000;  // per communication step
    int method = 0;           // IntegrationMethod
    int substeps = 1;         // real-time method: equal substeps per communication step

    // Derived by finalize(): the layout, dry friction per padded coordinate (a rigid axis merges its
    // rotor's friction into the load's), the share of a merged element attributed to the rotor, and
    // whether any disturbance element is on.
    StateLayout layout;
    DryFrictionParameters coordinate_friction[4];
    double rotor_friction_share[2] = {0, 0};
    void finalize();
    int state_size() const { return layout.size; }
};

// Dry friction regime of one coordinate. |qd| < w_min is the low-speed (stick candidate) region.
enum class FrictionMode : std::int8_t {
    none,               // coordinate without dry friction
    slip_positive,      // qd >= w_min: T_as = -T_din
    slip_negative,      // qd <= -w_min: T_as = +T_din
    hold,               // low speed, T_as = -T_outros - c_num qd within +-T_max (stuck)
    at_max_positive,    // low speed, T_as = +T_max (break-away, or the hold torque clipped)
    at_max_negative,    // low speed, T_as = -T_max
};

inline bool low_speed(FrictionMode mode) {
    return mode == FrictionMode::hold || mode == FrictionMode::at_max_positive || mode == FrictionMode::at_max_negative;
}

// Discrete state: constant between events, so that the right-hand side is smooth within a mode.
struct Modes {
    int gear_contact[2] = {0, 0};    // -1 at -eta, 0 in the gap (or no backlash), +1 at +eta
    int motor_limited[2] = {0, 0};   // -1 held at -i_L, 0 free, +1 held at +i_L
    int voltage_clamped[2] = {0, 0}; // a ramped voltage held at -U_L / +U_L (0: follows the ramp)
    FrictionMode friction[4] = {FrictionMode::none, FrictionMode::none, FrictionMode::none, FrictionMode::none};
    int axis_stop[kAxisStopCount] = {};  // per axis stop: -1 resting on the lower stop, 0 free (or off), +1 on the upper
    int amplifier_saturated[2] = {0, 0};  // current drive: -1 output held at -U_L, 0 free, +1 held at +U_L
};

// Inputs over one communication step: voltages held (or, when the master gives their derivatives,
// ramped), base motion at constant acceleration from the step start.
struct StepInputs {
    double voltage[2] = {0, 0};            // commanded at the step start, clamped to +-U_L
    double commanded_voltage[2] = {0, 0};  // as set, unclamped
    double voltage_rate[2] = {0, 0};       // fmi2SetRealInputDerivatives, order 1
    double current_command[2] = {0, 0};    // current drive: commanded at the step start, clamped to +-i_L
    double commanded_current[2] = {0, 0};  // as set, unclamped
    BaseMotion base;                       // at the step start
    double step_start_time = 0.0;
};

// The state in full form, whatever the fidelity.
struct FullState {
    Vec4 angle, rate;
    double current[2];   // the armature current (algebraic for a quasi-static motor, held at +-i_L when limited)
    double backlash[2];  // 0 without backlash
    double amplifier_integrator[2];  // x_I of a current-commanded inductive motor's amplifier, else 0
};

// Everything the right-hand side, the event functions and the outputs need, at one (t, x, modes).
struct Dynamics {
    FullState full;
    Vec4 acceleration;              // padded coordinates (0 for a rigid axis's rotor)
    Vec4 full_acceleration;         // all four bodies
    double current_rate[2];
    double backlash_rate[2];
    double free_backlash_rate[2];   // X of (2.81)
    double deflection[2];
    double deflection_rate[2];
    double shaft_torque[2];
    double steady_current[2];       // (u - k_emf w) / R
    Vec4 friction_torque;           // T_as per padded coordinate
    Vec4 other_torque;              // T_outros, meaningful for low-speed coordinates only
    double voltage[2];              // applied
    Mat4 reduced_mass;              // padded coordinates
    double stop_torque[kAxisStopCount];  // each axis stop's reaction on its coordinate while it rests on it
    double amplifier_demand[2];     // current drive: the amplifier's output before its bus limit (u_unsat), else 0
    double amplifier_rate[2];       // dx_I/dt (0 while saturated, without an integrator, or in voltage drive)
};

// Derivatives of the full generalized forces (or accelerations) with respect to the full state:
// columns q (0-3), qd (4-7), currents (8-9), theta_b (10-11), whatever the fidelity.
using Mat4x12 = Eigen::Matrix<double, 4, 12>;
using Row12 = Eigen::Matrix<double, 1, 12>;
enum JacobianColumn : int { kAngleColumn = 0, kRateColumn = 4, kCurrentColumn = 8, kBacklashColumn = 10 };

}  // namespace gimbal
