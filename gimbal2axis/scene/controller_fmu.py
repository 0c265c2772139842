"""A scene's built-in controller and sensors as the parameters of the controller FMU
(build/Gimbal2Axis-Controller.fmu, docs/controller_fmu.md), which runs the same C kernel: coupled
with the gimbal FMU by a co-simulation master, it computes the voltages the scene runner's loop
does. What the FMU does not have is refused with a SceneError saying what: the random sensor terms
(drawn from the scene's seed by numpy's generator, which a C FMU cannot reproduce), indirect
stabilization, the gyro's bandwidth filter, references other than the target, user controllers."""
from __future__ import annotations

import math

from ..errors import SceneError

KINDS = ("none", "pid", "state_feedback")   # controller.kind 0, 1, 2
PID_GAINS = ("kp", "ki", "kd", "k_gyro", "k_ff", "k_acc")


def _controller_values(controller, target_spec) -> dict:
    values = {"controller.kind": KINDS.index(controller.kind),
              "azimuth.u_limit": controller.u_limit[0], "elevation.u_limit": controller.u_limit[1]}
    if controller.kind == "none":
        values["constant.u_R1"], values["constant.u_R2"] = controller.voltage
        return values
    if list(controller.refs) != ["target", "target"]:
        raise SceneError("the controller FMU sets its points toward the [target] only: [controller] needs "
                         "reference = 'target' on both axes")
    if "type" in target_spec:
        # a moving target (gimbal2axis/target): its position comes in through the FMU's target inputs
        # (the ship-motion FMU's target table, ship_motion_fmu.target_table)
        values["target.moving"] = True
    else:
        values["target.azimuth"] = math.radians(target_spec["azimuth_deg"])
        values["target.elevation"] = math.radians(target_spec["elevation_deg"])
    if controller.kind == "pid":
        for name, axis in zip(("azimuth", "elevation"), controller.axes):
            values.update({f"{name}.{gain}": getattr(axis, gain) for gain in PID_GAINS})
            values[f"{name}.d_filter_s"], values[f"{name}.i_limit"] = axis.tau, axis.i_limit
        return values
    for row in range(2):
        values.update({f"state_feedback.K[{row + 1},{column + 1}]": controller.K[row][column] for column in range(4)})
        values[f"state_feedback.ki[{row + 1}]"] = controller.ki[row]
    values["state_feedback.rate_from_encoder"] = controller.rate_source == "encoder"
    return values


def _sensor_values(sensors) -> dict:
    if sensors.scheme != "direct":
        raise SceneError("the controller FMU has the direct scheme only (a gyro on the payload): "
                         "[sensors] stabilization = 'indirect' is not in it")
    if sensors.gyro_noise > 0 or sensors.imu_noise > 0:
        raise SceneError("the controller FMU has no random sensor terms: [sensors] gyro_noise_deg_s and "
                         "imu_attitude_noise_deg must be 0")
    values = {"encoder.resolution": float(sensors.resolution),
              "encoder.offset[1]": sensors.encoder_offset[0], "encoder.offset[2]": sensors.encoder_offset[1]}
    gyro = sensors.gyro
    if gyro is None:
        return values
    if gyro.angle_random_walk > 0 or gyro.bias_instability > 0 or gyro.rate_random_walk > 0 or any(gyro.bias != 0):
        raise SceneError("the controller FMU has the gyro's deterministic terms only: [sensors.gyro] angle random "
                         "walk, bias instability, rate random walk and bias must be 0")
    if gyro.bandwidth > 0:
        raise SceneError("the controller FMU has no gyro bandwidth filter: [sensors.gyro] bandwidth_hz must be 0")
    axes = gyro.axes()
    values.update({f"gyro.axes[{i + 1},{j + 1}]": float(axes[i, j]) for i in range(3) for j in range(3)})
    values.update({"gyro.enabled": True, "gyro.quantization": gyro.quantum, "gyro.delay_samples": gyro.delay})
    return values


def controller_fmu_parameters(scene, u_limit: tuple) -> dict:
    """{name: value} of the controller FMU's parameters for `scene`'s [controller], [target] and
    [sensors]; u_limit: the motors' voltage limits (the gimbal's motor1.U_L, motor2.U_L)."""
    controller = scene.controller(tuple(u_limit))
    if controller.kind not in KINDS:
        raise SceneError(f"the controller FMU runs the built-in controllers {', '.join(KINDS)}, "
                         f"not type {controller.kind!r}")
    return {**_controller_values(controller, scene.target_spec), **_sensor_values(scene.sensors())}
