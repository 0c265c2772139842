"""Scene files the tests write for runs whose physics does not matter."""


def cheap_scene(stop_time: float, step_size: float = 1e-3, output_interval: float | None = None,
                name: str | None = None) -> str:
    """The TOML of a cheap gimbal (rigid gears, motors without inductance, no dry friction) on a fixed
    base, with no [controller] table: for tests that need a run's length, files, clock or controller
    plumbing, not its physics. The caller appends its [controller] table."""
    head = f'name = "{name}"\n' if name is not None else ""
    return head + f"""stop_time = {stop_time}
step_size = {step_size}
output_interval = {output_interval if output_interval is not None else step_size}
[fidelity]
"gear1.model" = 0
"gear2.model" = 0
"motor1.model" = 0
"motor2.model" = 0
dry_friction = false
"base.fixed" = true
[base_motion]
type = "fixed"
"""
