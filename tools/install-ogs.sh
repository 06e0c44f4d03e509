#!/usr/bin/env bash
# Install OpenGeoSys 6 (PyPI `ogs`, its `ogs` binary and mesh tools) into a venv, for the slow
# test tier's cross-code verification only (studies/verification/ogs_compare.py). Never called by
# `make test`. Usage: tools/install-ogs.sh [VENV] (default .venv). Exit 0 if `ogs --version` runs.
# The wheel (ogs 6.5.9, cp313 manylinux_2_28 x86_64) is about 50 MB and pulls in pandas.
set -euo pipefail
VENV=${1:-.venv}
OGS_VERSION=${OGS_VERSION:-6.5.9}
PY="$VENV/bin/python"
if "$VENV/bin/ogs" --version >/dev/null 2>&1; then
    exit 0
fi
"$PY" -m pip install --quiet "ogs==$OGS_VERSION"
"$VENV/bin/ogs" --version >/dev/null
