"""Convert the published Panda log (Gaz et al. 2019) into torquebench's CSV form.

    python data/panda_gaz2019/convert.py SOURCE_DIR [OUT.csv.gz]

SOURCE_DIR holds the four files of `marcocognetti/FrankaEmikaPandaDynModel`,
`matlab/data/Exciting_Traj/Trajectory_1/rbt_log/`: exciting_traj_{time,positions,
velocity,torques}.txt (one number per line; positions, velocities and torques
sample-major, 7 numbers per sample). The output is the documented CSV form
`t, q1..q7, qd1..qd7, tau1..tau7`, every value written as the exact text of the
source (nothing rounded, nothing resampled), gzip-compressed with a fixed time
stamp so the file is reproducible byte for byte.
"""

from __future__ import annotations

import gzip
import sys
from pathlib import Path

DOF = 7
FILES = {"q": "exciting_traj_positions.txt", "qd": "exciting_traj_velocity.txt",
         "tau": "exciting_traj_torques.txt"}


def tokens(path: Path) -> list[str]:
    return [line.strip() for line in path.read_text().splitlines() if line.strip()]


def convert(source: Path, out: Path) -> int:
    """Write out; returns the number of samples."""
    t = tokens(source / "exciting_traj_time.txt")
    columns = {k: tokens(source / name) for k, name in FILES.items()}
    for k, values in columns.items():
        if len(values) != DOF * len(t):
            raise SystemExit(f"{FILES[k]}: {len(values)} numbers for {len(t)} samples x {DOF}")
    header = ["t"] + [f"{k}{j}" for k in FILES for j in range(1, DOF + 1)]
    lines = [",".join(header)]
    for i, stamp in enumerate(t):
        row = [stamp] + [v for k in FILES for v in columns[k][DOF * i:DOF * (i + 1)]]
        lines.append(",".join(row))
    with open(out, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=0,
                                               filename="", compresslevel=9) as f:
        f.write(("\n".join(lines) + "\n").encode())
    return len(t)


if __name__ == "__main__":
    src = Path(sys.argv[1])
    dst = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).parent / "panda_gaz2019.csv.gz"
    print(f"wrote {dst}: {convert(src, dst)} samples")
