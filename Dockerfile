# pilegroup on Debian's own FEniCSx packages (DOLFINx 0.11 from Debian unstable).
# Not exercised by CI: no container engine runs on the project's machines.
FROM debian:unstable-slim
RUN apt-get update \
 && apt-get install -y --no-install-recommends \
      python3-dolfinx python3-gmsh python3-pyvista python3-h5py python3-matplotlib python3-scipy \
      python3-tqdm python3-pytest python3-hypothesis python3-pip python3-setuptools \
      mpich make \
 && rm -rf /var/lib/apt/lists/*
WORKDIR /opt/pilegroup
COPY . .
# Debian's dolfinx has no dolfinx_solver module; pilegroup imports it only when present.
RUN pip install --no-deps --no-build-isolation --break-system-packages .
RUN pilegroup --help
CMD ["pilegroup", "--help"]
