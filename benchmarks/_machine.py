"""What every benchmark records about the machine and the software it ran on."""

from __future__ import annotations

import datetime
import os
import platform
from typing import Any

import numba as nb
import numpy as np
import scipy

import flexarm


def cpu_model() -> str:
    """The CPU model string from /proc/cpuinfo (or what platform knows)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info(**peers: Any) -> dict[str, Any]:
    """Date, CPU, load, versions of flexarm's stack and of each peer module given
    (``None`` for a peer that could not be imported)."""
    info: dict[str, Any] = {
        "date": datetime.date.today().isoformat(),
        "cpu": cpu_model(),
        "cpus": os.cpu_count(),
        "loadavg_at_start": list(os.getloadavg()),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": nb.__version__,
        "flexarm": flexarm.__version__,
    }
    for name, module in peers.items():
        info[name] = None if module is None else module.__version__
    info["OPENBLAS_NUM_THREADS"] = os.environ.get("OPENBLAS_NUM_THREADS")
    return info


def print_machine(machine: dict[str, Any], peer: str, label: str | None = None) -> None:
    """Print the header every report starts with: machine, versions (``peer`` is the
    key of the peer module in ``machine``, shown as ``label``) and load averages."""
    m = machine
    print()
    print(f"{m['date']}  {m['cpu']} ({m['cpus']} CPUs)  {m['platform']}")
    print(
        f"python {m['python']}  numpy {m['numpy']}  scipy {m['scipy']}  numba {m['numba']}  "
        f"flexarm {m['flexarm']}  {label or peer} {m.get(peer) or 'not installed'}"
    )
    la0 = ", ".join(f"{x:.2f}" for x in m["loadavg_at_start"])
    la1 = ", ".join(f"{x:.2f}" for x in m.get("loadavg_at_end", m["loadavg_at_start"]))
    print(f"load average at start {la0}; at end {la1}")
