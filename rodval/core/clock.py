"""The age of this process: a command's wall-clock budget (``--max-wall``) counts from the
moment the process started, so the interpreter's start-up and rodval's imports are inside it."""

from __future__ import annotations

import os


def process_age_s() -> float:
    """Seconds since this process started (Linux: /proc/self/stat's start time against
    /proc/uptime, 10 ms resolution); 0.0 where the system does not tell."""
    try:
        with open("/proc/self/stat") as fh:
            # the command name (field 2) may hold spaces: fields after its closing ")"
            fields = fh.read().rsplit(")", 1)[1].split()
        with open("/proc/uptime") as fh:
            uptime = float(fh.read().split()[0])
        started = int(fields[19]) / os.sysconf("SC_CLK_TCK")  # field 22, starttime
    except (OSError, ValueError, IndexError):
        return 0.0
    return max(uptime - started, 0.0)
