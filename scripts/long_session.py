#!/usr/bin/env python3
"""Makes a long session from a short one, for measuring long recordings (replay, export, GUI).

The source is played forward, then backward, then forward again... until the requested length:
joint angles, torques, the object's true pose and the camera stay continuous at every turn (a
recording played backward is still one the hand could have made, and each image still matches
the truth at its time). Images are hard links to the source's files where the file system allows
(a copy otherwise), so a 10-minute session costs little disk.

    scripts/long_session.py SOURCE OUT --minutes 10 [--overwrite]

Only the files readers use are written (session.json, joints.csv, camera.csv, groundtruth.csv,
images/, model/); the source's truth/ folder (simulator internals) is left out.
"""
import argparse
import csv
import json
import os
import shutil
import sys


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        sys.exit(f"long_session: {path}: empty, expected a header row")
    return rows[0], rows[1:]


def tile(rows, duration, t0, t_end, time_column=0):
    """The rows played forward and backward until `duration` seconds; times strictly increase."""
    span = t_end - t0
    if span <= 0:
        sys.exit("long_session: the source spans no time")
    out, last, k = [], None, 0
    while True:
        order = rows if k % 2 == 0 else rows[::-1]
        for row in order:
            local = float(row[time_column]) - t0
            t = t0 + k * span + (local if k % 2 == 0 else span - local)
            if t - t0 > duration + 1e-9:
                return out
            if last is not None and t <= last + 1e-9:
                continue  # the sample at a turn, already written
            last = t
            out.append([repr(t)] + row[1:])
        k += 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source")
    ap.add_argument("out")
    ap.add_argument("--minutes", type=float, required=True)
    ap.add_argument("--overwrite", action="store_true")
    a = ap.parse_args()
    if a.minutes <= 0:
        sys.exit("long_session: --minutes must be positive")
    src = a.source
    for name in ("session.json", "joints.csv"):
        if not os.path.isfile(os.path.join(src, name)):
            sys.exit(f"long_session: {os.path.join(src, name)}: missing, expected a session folder")
    if os.path.exists(a.out):
        if not a.overwrite:
            sys.exit(f"long_session: {a.out} exists (--overwrite replaces it)")
        shutil.rmtree(a.out)
    tmp = a.out.rstrip("/") + ".partial"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(os.path.join(tmp, "images"))

    header, joints = read_csv(os.path.join(src, "joints.csv"))
    t0, t_end = float(joints[0][0]), float(joints[-1][0])
    duration = a.minutes * 60.0

    def write(name, header, rows):
        with open(os.path.join(tmp, name), "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(header)
            w.writerows(rows)

    write("joints.csv", header, tile(joints, duration, t0, t_end))
    if os.path.isfile(os.path.join(src, "groundtruth.csv")):
        h, rows = read_csv(os.path.join(src, "groundtruth.csv"))
        write("groundtruth.csv", h, tile(rows, duration, t0, t_end))
    if os.path.isfile(os.path.join(src, "camera.csv")):
        h, rows = read_csv(os.path.join(src, "camera.csv"))
        image = h.index("image")
        frames = tile(rows, duration, t0, t_end)
        for i, row in enumerate(frames):
            ext = os.path.splitext(row[image])[1]
            name = f"images/frame_{i:06d}{ext}"
            target = os.path.join(tmp, name)
            try:
                os.link(os.path.join(src, row[image]), target)
            except OSError:
                shutil.copyfile(os.path.join(src, row[image]), target)
            row[image] = name
        write("camera.csv", h, frames)
    if os.path.isdir(os.path.join(src, "model")):
        shutil.copytree(os.path.join(src, "model"), os.path.join(tmp, "model"))
    with open(os.path.join(src, "session.json")) as f:
        info = json.load(f)
    info["name"] = f"{info.get('name', 'session')}-{a.minutes:g}min"
    info.setdefault("provenance", {})["long_session"] = {
        "source": os.path.abspath(src),
        "minutes": a.minutes,
        "how": "played forward and backward in turn",
    }
    info["provenance"]["duration"] = duration
    with open(os.path.join(tmp, "session.json"), "w") as f:
        json.dump(info, f, indent=2)
        f.write("\n")
    os.rename(tmp, a.out)


if __name__ == "__main__":
    main()
