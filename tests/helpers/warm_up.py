"""Compile into Numba's on-disk cache the kernels nearly every test calls, before
pytest-xdist's workers start (``tests/conftest.py`` runs this script).

From a cold cache every worker would otherwise compile the same kernels at the same
time (tens of seconds each: each entry inlines the whole dynamics); compiled once
here, the workers load them. The two shares, one process each, split the work about
evenly: the packed arm's entries; the public faces and the closed loop. A share that
fails changes nothing but the time (the tests then compile what they call).

``python tests/helpers/warm_up.py`` runs every share, each in a process of its own;
``python tests/helpers/warm_up.py SHARE`` runs share number ``SHARE``.
"""

from __future__ import annotations

import subprocess
import sys


def _packed() -> None:
    """The packed arm's entry points (compiled at import: what
    ``FlexibleArm.forward_dynamics``, ``mass_matrix`` and ``tip_position`` call)."""
    import numpy as np

    import flexarm as fa
    import flexarm.model.packed  # compiles its entry points

    arm = fa.FlexibleArm.paper()
    arm.forward_dynamics(np.full(arm.n_dof, 0.1), np.full(arm.n_dof, 0.2), np.ones(2))


def _faces_and_closed_loop() -> None:
    """The public dynamics kernels called from Python, for the one type signature
    their checks admit (C-contiguous float64 vectors, the read-only ``ArmArrays``),
    then the closed loop of the README's example (controller, sensor, RK4 step)."""
    import numpy as np

    import flexarm as fa
    from flexarm.control.controllers import JacobianTransposePD
    from flexarm.control.trajectories import Square
    from flexarm.model import dynamics

    arm = fa.FlexibleArm.paper()
    n = arm.n_dof
    q, dq, tau = np.full(n, 0.1), np.full(n, 0.2), np.ones(arm.n_links)
    for kernel in (
        dynamics.forward_dynamics,
        dynamics.forward_dynamics_general,
        dynamics.forward_dynamics_dense,
        dynamics.forward_dynamics_recursive,
    ):
        kernel(q, dq, tau, arm.arrays, dynamics.make_workspace(n), np.empty(n))
    fa.simulate(arm, JacobianTransposePD.from_arm(arm, zeta=0.707), Square(), duration=0.01)


SHARES = (_packed, _faces_and_closed_loop)


if __name__ == "__main__":
    if len(sys.argv) > 1:
        SHARES[int(sys.argv[1])]()
    else:
        shares = [
            subprocess.Popen(
                [sys.executable, __file__, str(i)],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            for i in range(len(SHARES))
        ]
        for share in shares:
            share.wait()
