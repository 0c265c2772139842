#!/usr/bin/env python3
"""Measure the frequency of a scene's sustained oscillation (the backlash limit cycle by default).

Runs the scene on the FMU (no files written), takes one recorded signal from --from-s (after the
transient) to the end, and times its upward crossings of its mean over that window, each by linear
interpolation between samples: frequency = (crossings - 1) / (time of the last - time of the first).
As a cross-check it also prints the peak of the signal's spectrum (Hann window; resolution 1 / window
length). The limit-cycle frequency in docs/scenes.md is what this prints for the default scene.

Usage: limit_cycle_frequency.py [scene.toml] [--fmu build/Gimbal2Axis.fmu] [--signal alpha] [--from-s 1]
"""
import argparse
import pathlib
import sys

import numpy as np

from scene_lib import FMU, SceneError, load_scene, run

REPO = pathlib.Path(__file__).resolve().parents[1]


def oscillation_frequency(t: np.ndarray, x: np.ndarray, from_s: float) -> dict:
    """Frequency [Hz] of x(t) over t >= from_s from its upward mean crossings, and its spectral peak."""
    window = t >= from_s
    t, x = t[window], x[window] - np.mean(x[window])
    up = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    if len(up) < 3:
        raise SceneError(f"the signal crosses its mean upwards {len(up)} times after {from_s:g} s: no sustained "
                         "oscillation to measure")
    crossings = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    frequency = (len(crossings) - 1) / (crossings[-1] - crossings[0])
    spectrum = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    bins = np.fft.rfftfreq(len(x), t[1] - t[0])
    return {"frequency": float(frequency), "cycles": len(crossings) - 1, "from": float(t[0]), "to": float(t[-1]),
            "spectral_peak": float(bins[1:][np.argmax(spectrum[1:])]), "resolution": float(1.0 / (t[-1] - t[0]))}


def measure(scene_path, fmu_path, signal: str = "alpha", from_s: float = 1.0) -> dict:
    scene = load_scene(scene_path)
    if not 0 <= from_s < scene.stop_time:
        raise SceneError(f"--from-s {from_s:g} must lie in [0, {scene.stop_time:g}) s, the scene's run")
    with FMU(fmu_path) as fmu:
        signals = run(scene, fmu).signals
    if signal not in signals:
        raise SceneError(f"no recorded signal '{signal}' (signals: {', '.join(sorted(signals))})")
    return dict(oscillation_frequency(signals["time"], np.asarray(signals[signal], dtype=float), from_s),
                scene=scene.name, signal=signal)


def describe(m: dict) -> str:
    return (f"{m['scene']}: {m['signal']} oscillates at {m['frequency']:.1f} Hz (period {1e3 / m['frequency']:.1f} ms; "
            f"{m['cycles']} cycles over [{m['from']:g}, {m['to']:g}] s; spectral peak {m['spectral_peak']:.1f} Hz "
            f"+- {m['resolution'] / 2:.2f} Hz)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "backlash_limit_cycle.toml"),
                        help="the scene file (default: scenes/backlash_limit_cycle.toml)")
    parser.add_argument("--fmu", default=str(REPO / "build" / "Gimbal2Axis.fmu"),
                        help="the FMU to run (default: build/Gimbal2Axis.fmu)")
    parser.add_argument("--signal", default="alpha", help="the recorded signal to measure (default: alpha)")
    parser.add_argument("--from-s", type=float, default=1.0,
                        help="start of the measured window in s, after the transient (default: 1)")
    args = parser.parse_args()
    try:
        print(describe(measure(args.scene, args.fmu, args.signal, args.from_s)))
    except SceneError as exc:
        print(f"limit_cycle_frequency.py: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
