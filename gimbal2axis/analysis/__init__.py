"""Analyses of the gimbal: its linear model A, B, C, D at an operating point (linearization.py, through
libgimbal_probe.so), frequency responses measured on the FMU by sine dwell (frequency_response.py; what a
freqresp dwell runs: dwell_plan.py), the linear prediction of a PID scene's closed loop: isolation ratio,
loop gain, margins (isolation_prediction.py; the prediction a dwell is drawn against: linear_prediction.py),
the checks of a dwell's points (point_checks.py), the margins of its measured loop gain
(measured_margins.py) and the scale of a sea-state estimate on an isolation dwell (carrier_projection.py)."""
