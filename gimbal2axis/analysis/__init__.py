"""Analyses of the gimbal: its linear model A, B, C, D at an operating point (linearization.py, through
libgimbal_probe.so), frequency responses measured on the FMU by sine dwell (frequency_response.py), and
the linear prediction of a PID scene's closed loop: isolation ratio, loop gain, margins
(isolation_prediction.py)."""
