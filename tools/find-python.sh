#!/usr/bin/env bash
# Print the path of a Python >= 3.12 on this machine, or explain and exit 1.
# Order: python3.13, python3.12, python3 (if new enough), pyenv's installed versions.
set -u
ok() { "$1" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 12) else 1)' 2>/dev/null; }
for c in python3.13 python3.12 python3; do
  p=$(command -v "$c" 2>/dev/null) || continue
  if ok "$p"; then echo "$p"; exit 0; fi
done
roots=()
if command -v pyenv >/dev/null 2>&1; then roots+=("$(pyenv root)"); fi
roots+=("${PYENV_ROOT:-}" "$HOME/.pyenv")
for r in "${roots[@]}"; do
  [ -n "$r" ] && [ -d "$r/versions" ] || continue
  for p in $(ls -d "$r"/versions/3.1[2-9]*/bin/python3 2>/dev/null | sort -rV); do
    if ok "$p"; then echo "$p"; exit 0; fi
  done
done
echo "pilegroup needs Python >= 3.12: none found as python3.13, python3.12, python3 or under pyenv." >&2
echo "Install one (e.g. 'pyenv install 3.12') or put it on PATH, then run make again." >&2
exit 1
