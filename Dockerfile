# pilegroup on Debian's own FEniCSx packages (DOLFINx 0.11 from Debian unstable).
# No container engine runs on the project's machines: tools/container-smoke.sh follows these
# instructions in a debootstrap root of Debian unstable and runs the smoke tests in it
# (docs/container.md, with its last result). Build, run and test commands: README, "Docker".
FROM debian:unstable-slim
ARG DEBIAN_FRONTEND=noninteractive
# Debian builds DOLFINx, petsc4py, mpi4py and HDF5 on Open MPI: openmpi-bin is their mpirun.
# python3-venv, ruff and make serve `make test` in the image (SYSTEM_PACKAGES below).
RUN apt-get update \
 && apt-get install -y --no-install-recommends \
      python3-dolfinx python3-gmsh python3-pyvista python3-h5py python3-matplotlib python3-scipy \
      python3-tqdm python3-pytest python3-hypothesis python3-pip python3-setuptools python3-venv \
      openmpi-bin ruff make \
 && rm -rf /var/lib/apt/lists/*
# Open MPI refuses to start as root: the image runs as an ordinary user, owner of the sources
# (tests and runs write under /opt/pilegroup: .venv, out/, caches).
RUN useradd --create-home --uid 1000 --shell /bin/bash pilegroup \
 && install -d -o pilegroup -g pilegroup /opt/pilegroup
WORKDIR /opt/pilegroup
COPY --chown=pilegroup:pilegroup . .
USER pilegroup
# `make test` / `make run` (and this `make bootstrap`) make .venv over the system's packages
# (Makefile, SYSTEM_PACKAGES): Debian's DOLFINx, PETSc and Open MPI, never PyPI's wheels;
# pilegroup in it in editable mode (the sources here are what runs and what the tests test), and
# Open MPI's mpirun linked into its bin/, which comes first on PATH. Debian's dolfinx has no
# dolfinx_solver module; pilegroup imports it only when present. Open MPI may start more ranks
# than the container has cores (the tests start up to 4; MPICH does so without asking).
ENV SYSTEM_PACKAGES=1 \
    PATH=/opt/pilegroup/.venv/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    PRTE_MCA_mapby=:oversubscribe
RUN make bootstrap && pilegroup --help > /dev/null
# `docker stop` sends SIGUSR1: a run stops at its next step boundary with a checkpoint, and Open
# MPI's mpirun forwards it to the ranks (on SIGTERM it kills them at once: docs/checkpoint.md,
# "Signals"). Give a large run the time to reach the boundary: `docker stop -t 120`.
STOPSIGNAL SIGUSR1
CMD ["pilegroup", "--help"]
