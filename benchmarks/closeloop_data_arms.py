"""`closeloop --data` on simulated logs of arms with known joint effects.

The arm plants of the "arm_closeloop" bench section (harness.sections.arm_closeloop.PLANTS:
viscous 0.8 N m s/rad on joint 2, Coulomb 1.5 N m on joint 3, armature 0.1 kg m^2 on joint
1, a 3 N m/rad spring on joint 4, a 1 kg flange payload) are simulated in MuJoCo
(generate(..., 4000 samples, 5 % noise, "measured")), and the data alone go through the
measured-data loop (identification.closeloop.measured) on the arm's rigid-body atoms. The
payload, and an armature on a joint whose rotor inertia the rigid-body atoms already hold
(the UR5's vertical joint 1), are rigid-body dynamics the declared model carries: not
named. Prints the named effects beside the plant's, the held-out errors before and after
and the unexplained joints, with the CPU time.

    python -m benchmarks.closeloop_data_arms [ur5 panda]   (from the checkout)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from harness.closeloop.arm_plants import write_arm_variant  # noqa: E402
from harness.closeloop.measured import rigid_library  # noqa: E402
from harness.data.generate import generate  # noqa: E402
from harness.sections.arm_closeloop import PLANTS  # noqa: E402
from identification.closeloop.measured import close_loop_measured  # noqa: E402


def run(robot: str, directory: Path) -> None:
    variant = PLANTS[0]
    start = time.process_time()
    data = generate(str(write_arm_variant(robot, variant, directory)), 4000, 0.05, 0, "measured", 0.0)
    loop = close_loop_measured(rigid_library(robot), data.q, data.qd, data.qdd, data.tau)
    named = {(t.effect, t.joint): t.coefficient for t in loop.terms}
    print(f"{robot}: CPU {time.process_time() - start:.1f} s (simulation included)")
    for effect, joint, value in variant.joint_effects:
        found = named.pop((effect, joint), None)
        text = "not named" if found is None else f"{found:.4g} ({(found - value) / value:+.1%})"
        print(f"  {effect:9s} joint {joint}: plant {value:g}, named {text}")
    print(f"  payload {variant.payload:g} kg: carried by the rigid-body atoms (no candidate)")
    extra = ", ".join(f"{e} joint {j} {c:.3g}" for (e, j), c in sorted(named.items()))
    print(f"  named beyond these: {extra or 'none'} (the URDF's own joint damping, if any, is "
          "in the plant and not in the rigid-body model)")
    fmt = ", ".join
    print(f"  held-out error before [{fmt(f'{e:.4f}' for e in loop.error_before)}]")
    print(f"                 after  [{fmt(f'{e:.4f}' for e in loop.error_after)}]")
    print(f"  unexplained joints: {list(loop.unexplained_joints) or 'none'}; structure removed "
          f"[{fmt(f'{e:.2f}' for e in np.clip(loop.explained, 0, 1))}]")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        for name in sys.argv[1:] or ["ur5", "panda"]:
            run(name, Path(tmp))
