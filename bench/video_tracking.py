"""Benchmark: tracking the markers of a filmed test, 20 s at 240 frames per second, on one core.

    python bench/video_tracking.py --out results/bench [--seconds 20] [--fps 240]

Films a rocking wall (:func:`rocklab.lab.virtual_native.write_video`, the
film of :data:`rocklab.lab.virtual_native.BENCH_FILM`: 480 x 360 pixels,
noise, motion blur, a tilted camera, two short occlusions, MPEG-4) and
times :func:`rocklab.lab.video_tracking.track_video` on it, OpenCV held
to one thread and the process to one core where the system allows it; the
time is the process's CPU time over the tracking (robust on a shared
machine) beside the wall time.  Writes
``<out>/video_tracking.json`` with both times, the frames, the frames
tracked and theta's error against the filmed motion, and exits 1 when the
CPU time is over the target of issue 43 (20 s).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: Longest tracking of a 20 s film at 240 frames per second [s] (issue 43).
TARGET_S = 20.0


def rocking(n: int, fs: float) -> np.ndarray:
    """A rocking-like theta [rad]: a wall released at 0.08 rad whose swings die out in about 12 s."""
    t = np.arange(n) / fs
    return 0.08 * np.cos(2 * np.pi * 0.9 * t) * np.clip(1 - t / 12, 0, 1) ** 2


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--fps", type=float, default=240.0)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    import cv2

    from rocklab.lab.video_tracking import track_video
    from rocklab.lab.virtual_native import BENCH_FILM, write_video

    cv2.setNumThreads(1)
    spec = {"length_mm": 1420.0, "height_mm": 1090.0, "thickness_mm": 113.0}
    n = int(round(args.seconds * args.fps))
    theta = rocking(n, args.fps)
    effects = BENCH_FILM
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "film.mp4"
        t0 = time.perf_counter()
        write_video(path, args.fps, theta, np.zeros(n), spec, effects, rng=0)
        render_s = time.perf_counter() - t0
        size_mb = path.stat().st_size / 1e6
        cpu0, t0 = time.process_time(), time.perf_counter()
        tr = track_video(path, progress=False)
        cpu_s, wall_s = time.process_time() - cpu0, time.perf_counter() - t0
    err = tr.theta - theta
    seen = np.isfinite(err)
    out = {
        "seconds": args.seconds,
        "fps": args.fps,
        "frames": n,
        "frame_px": [effects.height_px, effects.width_px],
        "film_mb": round(size_mb, 2),
        "render_s": round(render_s, 2),
        "track_cpu_s": round(cpu_s, 2),
        "track_wall_s": round(wall_s, 2),
        "frames_per_s": round(n / cpu_s, 1),
        "frames_tracked": tr.frames_tracked,
        "theta_abs_error_median_rad": float(np.median(np.abs(err[seen]))),
        "theta_abs_error_max_rad": float(np.max(np.abs(err[seen]))),
        "tracking_noise_rad": tr.noise_rad,
        "target_s": TARGET_S,
        "pass": bool(cpu_s <= TARGET_S),
    }
    (args.out / "video_tracking.json").write_text(json.dumps(out, indent=1) + "\n")
    print(f"tracked {n} frames in {cpu_s:.1f} s CPU ({wall_s:.1f} s wall), target {TARGET_S:g} s")
    return 0 if out["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
