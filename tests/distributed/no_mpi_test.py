#!/usr/bin/env python3
"""A sidc built without MPI, started by a launcher as two copies (the environment mpirun sets):
rank 0 says why it refuses and how to get the MPI build, rank 1 says nothing, both exit 2 (usage),
and no file is written. Without that environment the same binary fits as always.

Usage: no_mpi_test.py SIDC REPO
"""
import os
import subprocess
import sys
import tempfile

sidc, repo = sys.argv[1], sys.argv[2]
example = os.path.join(repo, "examples", "thesis-4-1")
failures = []
with tempfile.TemporaryDirectory() as out:
    for rank in (0, 1):
        env = dict(os.environ, OMPI_COMM_WORLD_SIZE="2", OMPI_COMM_WORLD_RANK=str(rank))
        run = subprocess.run([sidc, "fit", "system_4_1_1.sid", "--out", os.path.join(out, "fit")], cwd=example, env=env,
                             capture_output=True, text=True, timeout=60)
        said = "built without MPI" in run.stderr and "libopenmpi-dev" in run.stderr
        if run.returncode != 2 or said != (rank == 0) or run.stdout:
            failures.append(f"rank {rank}: exit {run.returncode}, stdout {run.stdout[:200]!r}, stderr {run.stderr!r}")
    if os.path.exists(os.path.join(out, "fit")):
        failures.append("a file was written")
    plain = subprocess.run([sidc, "fit", "system_4_1_1.sid"], cwd=example, capture_output=True, text=True, timeout=60)
    if plain.returncode != 0 or "sidc fit: model" not in plain.stdout:
        failures.append(f"without a launcher: exit {plain.returncode}")
for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
