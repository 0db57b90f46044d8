"""Exudyn models of flexarm's arms: the outside flexible-multibody oracle.

Exudyn (https://github.com/jgerstmayr/EXUDYN, PyPI ``exudyn``) is a C++ flexible
multibody engine that no one here wrote. Each flexarm link becomes a chain of
geometrically exact ANCF cable elements (``ObjectANCFCable2D``: Euler–Bernoulli
bending with the exact kinematics of large deflection and an axial strain), so
foreshortening, centrifugal stiffening and the coupling of the links come out
of the finite elements rather than of an assumed-mode expansion. The reference
shares with flexarm only the physical data (lengths, ``EI``, ``rho A``, hubs,
payload) and the definitions of the outputs:

* joint ``i`` is a revolute joint between the previous link's tip (or the
  ground) and a hub body clamped to link ``i``'s root; the joint angle is the
  hub's angle minus the direction of the previous link's tip tangent (flexarm's
  convention: joint ``i`` turns link ``i`` relative to the deflected tip);
* a hub is a rigid body at the joint: ``hub_mass`` and ``hub_inertia`` of
  :class:`flexarm.Link` (a hubless joint gets 1e-9 kg and 1e-12 kg m**2, below
  anything the comparisons resolve, to keep the mass matrix regular);
* the payload is a rigid body clamped to the last tip;
* the tip deflection of a link is its tip's offset from its root, across the
  root's tangent (flexarm's link frame);
* gravity (``gravity=(g_x, g_y)``, m/s**2) is Exudyn's mass-proportional load on
  every cable element, hub and the payload.

The axial stiffness ``EA`` is not part of flexarm's inextensible model; it is
set from a slenderness ``L / r`` (radius of gyration ``r``, ``EA = EI / r**2``)
of 300 unless given: the axial strains it allows (centrifugal tension over
``EA``) are below 1e-4 in every comparison here.

Time integration: Exudyn's implicit generalised-alpha (spectral radius 0.9) with a
fixed step; Newton's absolute tolerance is 1e-6 (N, N m) — the default 1e-10
cannot be met once the loads vanish and makes the solver shrink its step to
nothing. Torques and prescribed motions are Exudyn *symbolic* user functions
(compiled expressions: a Python callback would be called for every column of
every numerical Jacobian).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

import flexarm as fa

try:  # the oracle is optional: the tests that need it skip without it
    import exudyn as exu
    from exudyn import itemInterface as ei
    from exudyn.utilities import CreateSymbolicUserFunction
except ImportError as _exc:  # pragma: no cover - depends on the machine
    exu = None
    EXUDYN_MISSING = f"Exudyn is not installed ({_exc}); pip install exudyn (the 'test' extra)"
else:
    EXUDYN_MISSING = ""

__all__ = [
    "EXUDYN_MISSING",
    "ExudynRun",
    "KaneSpinUp",
    "TorquePulses",
    "run_exudyn",
]

SLENDERNESS = 300.0


@dataclass(frozen=True)
class TorquePulses:
    """Joint torques ``tau_i(t) = amplitude_i sin**2(pi t / duration_i)`` for
    ``t < duration_i``, then 0 (N m): smooth, zero rate at both ends."""

    amplitude: tuple[float, ...]
    duration: tuple[float, ...]

    def __call__(self, t: float) -> np.ndarray:
        """The torques at ``t`` (s), shape (n_links,), for flexarm."""
        a, d = np.asarray(self.amplitude), np.asarray(self.duration)
        return np.where(t < d, a * np.sin(np.pi * t / d) ** 2, 0.0)

    def symbolic(self, i: int) -> Any:
        """Joint ``i``'s torque as an Exudyn symbolic expression of ``t``."""
        esym = exu.symbolic
        a, d = float(self.amplitude[i]), float(self.duration[i])

        def torque(t: Any) -> Any:
            s = esym.sin(math.pi / d * t)
            return esym.IfThenElse(t < d, a * s * s, 0.0 * t)

        return torque


@dataclass(frozen=True)
class KaneSpinUp:
    """The spin-up of Kane, Ryan & Banerjee (J. Guid. Control Dyn. 10(2), 1987):
    ``theta(t) = (Omega / T)[t**2 / 2 + (T / 2 pi)**2 (cos(2 pi t / T) - 1)]`` for
    ``t < T``, then ``Omega t - Omega T / 2`` (``Omega = 6 rad/s, T = 15 s`` in
    the paper)."""

    omega: float = 6.0
    ramp: float = 15.0

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(theta, dtheta, ddtheta)`` at times ``t`` (s), each of shape (m, 1)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        w, T = self.omega, self.ramp
        c = T / (2 * np.pi)
        on = t < T
        th = np.where(on, w / T * (t**2 / 2 + c**2 * (np.cos(t / c) - 1)), w * t - w * T / 2)
        dth = np.where(on, w / T * (t - c * np.sin(t / c)), w)
        ddth = np.where(on, w / T * (1 - np.cos(t / c)), 0.0)
        return th[:, None], dth[:, None], ddth[:, None]


@dataclass(frozen=True)
class ExudynRun:
    """Exudyn's answer on an even time grid.

    t : (K,) s; theta : (K, N) joint angles, rad; deflection : (K, N) each
    link's tip deflection across its root tangent, m; tip : (K, 2) the last
    link's tip, m; wall_s : solver time, s.
    """

    t: np.ndarray
    theta: np.ndarray
    deflection: np.ndarray
    tip: np.ndarray
    wall_s: float


def _cable_nodes(mbs: Any, x0: np.ndarray, phi: float, length: float, n: int) -> list[Any]:
    le = length / n
    c, s = math.cos(phi), math.sin(phi)
    return [
        mbs.AddNode(
            ei.NodePoint2DSlope1(
                referenceCoordinates=[x0[0] + k * le * c, x0[1] + k * le * s, c, s]
            )
        )
        for k in range(n + 1)
    ]


def run_exudyn(
    arm: fa.FlexibleArm,
    drive: TorquePulses | KaneSpinUp | Any,
    *,
    t_end: float,
    dt_out: float,
    n_elements: int = 8,
    step: float = 1e-3,
    axial_stiffness: tuple[float, ...] | None = None,
    gravity: tuple[float, float] | None = None,
) -> ExudynRun:
    """Simulate ``arm`` (straight, at rest, along x at ``t = 0``) in Exudyn.

    ``drive`` is :class:`TorquePulses` (joint torques) or a joint motion
    ``motion(t) -> (theta, dtheta, ddtheta)`` (shapes (m, n_links); the joint
    angles are prescribed, as :func:`flexarm.sim.prescribed.simulate_prescribed`
    prescribes them; the arm starts straight at ``theta(0)``, at rest).
    ``n_elements`` ANCF elements per link; ``step`` the integrator's step (s);
    outputs every ``dt_out`` s; ``gravity`` (m/s**2, base frame) pulls on every
    mass.

    A prescribed angle is a symbolic variable that a pre-step function sets, once
    per step, to the motion at the step's end time (where Exudyn's
    generalised-alpha enforces the constraint), so the joint follows the motion
    exactly at every step.
    """
    if exu is None:  # pragma: no cover
        raise RuntimeError(EXUDYN_MISSING)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ei.ObjectGround())
    torque_driven = isinstance(drive, TorquePulses)
    n_links = arm.n_links
    theta0 = np.zeros(n_links) if torque_driven else np.asarray(drive(np.zeros(1))[0]).reshape(-1)
    phi0 = np.cumsum(theta0)  # absolute angles of the straight arm at t = 0
    esym = exu.symbolic
    names = [f"flexarm_theta{i}_{id(mbs)}" for i in range(n_links)]
    x0 = np.zeros(2)
    prev_tip = None
    hubs, roots, tips = [], [], []
    weighed: list[Any] = []  # bodies that gravity pulls on
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for i, lk in enumerate(arm.links):
            L, EI, rho = lk.length, lk.flexural_rigidity, lk.linear_density
            EA = EI * (SLENDERNESS / L) ** 2 if axial_stiffness is None else axial_stiffness[i]
            nodes = _cable_nodes(mbs, x0, phi0[i], L, n_elements)
            for k in range(n_elements):
                cable = mbs.AddObject(
                    ei.ObjectANCFCable2D(
                        length=L / n_elements,
                        massPerLength=rho,
                        bendingStiffness=EI,
                        axialStiffness=EA,
                        nodeNumbers=[nodes[k], nodes[k + 1]],
                    )
                )
                weighed.append(cable)
            nh = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[x0[0], x0[1], phi0[i]]))
            mass = lk.hub_mass if i > 0 and lk.hub_mass > 0 else 1e-9
            bh = mbs.AddObject(
                ei.ObjectRigidBody2D(nodeNumber=nh, mass=mass, inertia=max(lk.hub_inertia, 1e-12))
            )
            weighed.append(bh)
            m_hub = mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=bh))
            m_root = mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=nodes[0]))
            mbs.AddObject(
                ei.ObjectJointGeneric(
                    markerNumbers=[m_root, m_hub], constrainedAxes=[1, 1, 0, 0, 0, 1]
                )
            )
            if prev_tip is None:
                m_base = mbs.AddMarker(
                    ei.MarkerBodyRigid(bodyNumber=ground, localPosition=[x0[0], x0[1], 0])
                )
            else:
                m_base = mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=prev_tip))
            if torque_driven:
                if prev_tip is None:
                    m_bp = mbs.AddMarker(
                        ei.MarkerBodyPosition(bodyNumber=ground, localPosition=[x0[0], x0[1], 0])
                    )
                else:
                    m_bp = mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=prev_tip))
                m_hp = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=bh))
                mbs.AddObject(ei.ObjectJointRevolute2D(markerNumbers=[m_bp, m_hp]))
                fn = drive.symbolic(i)
                _torque_load(mbs, m_hub, fn, 1.0)
                if prev_tip is not None:
                    _torque_load(mbs, m_base, fn, -1.0)  # the reaction on the carrier
            else:
                joint = mbs.AddObject(
                    ei.ObjectJointGeneric(
                        markerNumbers=[m_base, m_hub], constrainedAxes=[1, 1, 0, 0, 0, 1]
                    )
                )
                esym.variables.Set(names[i], float(theta0[i]))
                _prescribe(mbs, joint, names[i], float(theta0[i]))
            hubs.append(nh)
            roots.append(nodes[0])
            tips.append(nodes[-1])
            prev_tip = nodes[-1]
            x0 = x0 + L * np.array([math.cos(phi0[i]), math.sin(phi0[i])])
        if not torque_driven:

            def pre_step(mbs_: Any, t: float) -> bool:
                # t is the end of the step about to be taken
                th = np.asarray(drive(np.array([t]))[0], dtype=float).reshape(-1)
                for i in range(n_links):
                    esym.variables.Set(names[i], float(th[i]))
                return True

            mbs.SetPreStepUserFunction(pre_step)
        if arm.payload_mass > 0 or arm.payload_inertia > 0:
            npl = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[x0[0], x0[1], phi0[-1]]))
            bpl = mbs.AddObject(
                ei.ObjectRigidBody2D(
                    nodeNumber=npl,
                    mass=max(arm.payload_mass, 1e-9),
                    inertia=max(arm.payload_inertia, 1e-12),
                )
            )
            mbs.AddObject(
                ei.ObjectJointGeneric(
                    markerNumbers=[
                        mbs.AddMarker(ei.MarkerNodeRigid(nodeNumber=prev_tip)),
                        mbs.AddMarker(ei.MarkerBodyRigid(bodyNumber=bpl)),
                    ],
                    constrainedAxes=[1, 1, 0, 0, 0, 1],
                )
            )
            weighed.append(bpl)
        if gravity is not None:
            load = [float(gravity[0]), float(gravity[1]), 0.0]
            for body in weighed:
                marker = mbs.AddMarker(ei.MarkerBodyMass(bodyNumber=body))
                mbs.AddLoad(ei.LoadMassProportional(markerNumber=marker, loadVector=load))
        coords = exu.OutputVariableType.Coordinates

        def sensor(node: Any) -> Any:
            return mbs.AddSensor(
                ei.SensorNode(
                    nodeNumber=node,
                    outputVariableType=coords,
                    storeInternal=True,
                    writeToFile=False,
                )
            )

        s_hub = [sensor(n) for n in hubs]
        s_root = [sensor(n) for n in roots]
        s_tip = [sensor(n) for n in tips]
        mbs.Assemble()
        st = exu.SimulationSettings()
        st.timeIntegration.numberOfSteps = round(t_end / step)
        st.timeIntegration.endTime = t_end
        st.timeIntegration.verboseMode = 0
        st.timeIntegration.newton.absoluteTolerance = 1e-6
        st.solutionSettings.writeSolutionToFile = False
        st.solutionSettings.sensorsWritePeriod = dt_out
        import time

        start = time.perf_counter()
        mbs.SolveDynamic(st)
        wall = time.perf_counter() - start
        hub = [mbs.GetSensorStoredData(s) for s in s_hub]
        root = [mbs.GetSensorStoredData(s) for s in s_root]
        tip = [mbs.GetSensorStoredData(s) for s in s_tip]
    t = hub[0][:, 0]
    theta, defl = [], []
    carrier = np.zeros_like(t)  # direction of the previous tip's tangent
    x0 = np.zeros(2)
    tip_pos = np.zeros((t.shape[0], 2))
    for i, lk in enumerate(arm.links):
        c, s_ = math.cos(phi0[i]), math.sin(phi0[i])
        phi = hub[i][:, 3] + phi0[i]
        theta.append(phi - carrier)
        r0 = x0 + root[i][:, 1:3]
        tip_pos = x0 + lk.length * np.array([c, s_]) + tip[i][:, 1:3]
        d = tip_pos - r0
        defl.append(-np.sin(phi) * d[:, 0] + np.cos(phi) * d[:, 1])
        carrier = np.unwrap(np.arctan2(s_ + tip[i][:, 4], c + tip[i][:, 3]))
        x0 = x0 + lk.length * np.array([c, s_])
    return ExudynRun(t, np.array(theta).T, np.array(defl).T, tip_pos, wall)


def _torque_load(mbs: Any, marker: Any, fn: Any, sign: float) -> None:
    load = mbs.AddLoad(ei.LoadTorqueVector(markerNumber=marker, loadVector=[0.0, 0.0, sign]))

    def uf(mbs_: Any, t: Any, v: Any) -> Any:
        return [0, 0, v[2] * fn(t)]

    sym = CreateSymbolicUserFunction(mbs, uf, "loadVectorUserFunction", load)
    mbs.SetLoadParameter(load, "loadVectorUserFunction", sym)


def _prescribe(mbs: Any, joint: Any, name: str, theta0: float) -> None:
    """Joint ``joint``'s relative rotation (between the two markers' current frames,
    so the joint angle itself) follows the symbolic variable ``name``."""
    del theta0
    esym = exu.symbolic

    def offset(mbs_: Any, t: Any, item: Any, p: Any) -> Any:
        return [0, 0, 0, 0, 0, esym.variables.Get(name)]

    sym = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
    mbs.SetObjectParameter(joint, "offsetUserFunction", sym)
