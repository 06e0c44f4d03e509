#!/usr/bin/env bash
# The Docker image without a container engine, and its smoke tests (docs/container.md).
#
# Builds the image's file system in a root of Debian unstable made by debootstrap, following the
# Dockerfile's instructions one by one (FROM, ARG, ENV, RUN, USER, WORKDIR, COPY, CMD,
# STOPSIGNAL): RUN is `/bin/sh -c` through chroot as the Dockerfile's USER with its ENV and
# WORKDIR, COPY honours .dockerignore. Then, as the image's user (as `docker run` would):
#   1. pilegroup --help;
#   2. pilegroup run single_pile (serial) and mpirun -n 2 pilegroup run single_pile, timed; the
#      image's STOPSIGNAL to a 2-rank run (what `docker stop` does): checkpoint, 128 + signal;
#   3. the tests: `make test` (ruff and the fast tier, against Debian's packages, the hypre
#      preset's tests included: Debian's PETSc has hypre) or a subset and `make test-hypre`;
#   4. the cap settlement of both runs against a serial run in the repository's .venv (if any).
# and prints a Markdown summary (also in ROOT/smoke-result.md).
#
# Usage (as root; needs debootstrap): tools/container-smoke.sh [--root DIR] [--tests WHICH]
#   --root DIR    where the roots live (default /work/sid-root): DIR/base (debootstrap, made
#                 once), DIR/deps (the Dockerfile up to its first COPY, remade when those
#                 instructions change: Docker's layer cache), DIR/image (remade on every call,
#                 an overlay over DIR/deps: mounted while the script runs)
#   --tests WHICH fast: `make test` in the image (default); smoke: ruff and the subset in
#                 SMOKE_TESTS below; none: no tests
# Idempotent: run it again after changing the Dockerfile or the sources.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
root=/work/sid-root
tests=fast
mirror=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
# The smoke subset: scenario input, laws, install, a serial and a 2-rank CLI run, checkpoints.
SMOKE_TESTS="tests/model tests/constitutive tests/package tests/studies/test_cli.py
tests/studies/test_checkpoint.py"

while [ $# -gt 0 ]; do
  case $1 in
    --root) root=$2; shift 2 ;;
    --tests) tests=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "container-smoke: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case $tests in fast|smoke|none) ;; *) echo "container-smoke: --tests fast|smoke|none" >&2; exit 2 ;; esac
[ "$(id -u)" = 0 ] || { echo "container-smoke: run as root (debootstrap, chroot, mounts)" >&2; exit 2; }
command -v debootstrap >/dev/null || { echo "container-smoke: needs debootstrap (apt-get install debootstrap)" >&2; exit 2; }

log() { printf '[container-smoke %s] %s\n' "$(date +%H:%M:%S)" "$*" >&2; }

# ---- mounts of a root while commands run in it (undone on exit) -----------------------------
mounted=()
mount_root() {  # the kernel file systems a container has: /proc, /sys, /dev/pts, /dev/shm
  local r=$1
  mount -t proc proc "$r/proc"; mounted+=("$r/proc")
  mount --bind /sys "$r/sys"; mount -o remount,bind,ro "$r/sys"; mounted+=("$r/sys")
  mkdir -p "$r/dev/pts" "$r/dev/shm"
  mount -t devpts -o newinstance,ptmxmode=0666 devpts "$r/dev/pts"; mounted+=("$r/dev/pts")
  mount -t tmpfs -o mode=1777,size=1g shm "$r/dev/shm"; mounted+=("$r/dev/shm")
  cp /etc/resolv.conf "$r/etc/resolv.conf"
}
umount_all() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do
    umount "${mounted[i]}" 2>/dev/null || umount -l "${mounted[i]}" 2>/dev/null || true
  done
  mounted=()
}
trap umount_all EXIT

# Mounts left by a run that was killed (the trap did not run): undone before anything is removed.
findmnt -rn -o TARGET | awk -v r="$root/" 'index($0, r) == 1' | sort -r \
  | while read -r m; do umount "$m" 2>/dev/null || umount -l "$m"; done

# ---- 1. the base: what FROM debian:unstable-slim gives ----------------------------------------
base=$root/base
if [ ! -e "$base/.complete" ]; then
  log "debootstrap of Debian unstable (minbase) into $base"
  rm -rf "$base"; mkdir -p "$root"
  debootstrap --variant=minbase unstable "$base" "$mirror" > "$root/debootstrap.log" 2>&1 \
    || { tail -20 "$root/debootstrap.log" >&2; exit 1; }
  touch "$base/.complete"
fi
# The slim image's apt and dpkg settings (no .deb kept, no docs or manuals), no package lists;
# and the archive reachable from the project's machines may serve a Release file past its
# Valid-Until date, which apt refuses unless told.
cat > "$base/etc/apt/apt.conf.d/docker-clean" <<'EOF'
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache ""; Dir::Cache::srcpkgcache "";
EOF
cat > "$base/etc/dpkg/dpkg.cfg.d/docker" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/groff/*
path-exclude /usr/share/info/*
path-exclude /usr/share/lintian/*
path-exclude /usr/share/linda/*
path-exclude /usr/share/locale/*
EOF
echo 'Acquire::Check-Valid-Until "false";' > "$base/etc/apt/apt.conf.d/99check-valid-until"
rm -rf "$base/var/lib/apt/lists/"*

# ---- 2. the Dockerfile's instructions ---------------------------------------------------------
# One instruction per element: continuation lines joined, comments and blank lines dropped.
mapfile -t instr < <(sed -e '/^[[:space:]]*#/d' "$repo/Dockerfile" \
  | awk '{ if (sub(/\\[[:space:]]*$/, "")) { buf = buf $0 " "; next } print buf $0; buf = "" }' \
  | sed -e '/^[[:space:]]*$/d')
first_copy=-1
for i in "${!instr[@]}"; do
  if [[ ${instr[i]} == COPY* ]]; then first_copy=$i; break; fi
done
[ "$first_copy" -ge 0 ] || { echo "container-smoke: the Dockerfile has no COPY" >&2; exit 1; }
[[ ${instr[0]} == "FROM debian:unstable-slim" ]] \
  || { echo "container-smoke: expects 'FROM debian:unstable-slim', found '${instr[0]}'" >&2; exit 1; }

# The state of the build as Docker keeps it.
declare -A env_vars
user=root
workdir=/
cmd=
stopsignal=SIGTERM

uid_of() { chroot "$1" id -u "$2"; }
gid_of() { chroot "$1" id -g "$2"; }
home_of() { chroot "$1" getent passwd "$2" | cut -d: -f6; }

# Run a shell command in root $1 as the build's current user, with its ENV and WORKDIR.
in_root() {
  local r=$1 c=$2 uid gid home
  uid=$(uid_of "$r" "$user"); gid=$(gid_of "$r" "$user"); home=$(home_of "$r" "$user")
  local envs=(HOME="${home:-/}" PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
              HOSTNAME=pilegroup-smoke)
  local k
  for k in "${!env_vars[@]}"; do envs+=("$k=${env_vars[$k]}"); done
  chroot --userspec="$uid:$gid" --groups="$gid" "$r" /usr/bin/env -i "${envs[@]}" \
    /bin/sh -c "cd \"\$1\" && eval \"\$2\"" sh "$workdir" "$c"
}

# Assignments of ARG/ENV lines: KEY=VALUE ... (values without spaces) or KEY VALUE.
set_vars() {
  local line=$1 kv
  if [[ $line != *=* ]]; then env_vars[${line%% *}]=${line#* }; return; fi
  for kv in $line; do
    [[ $kv == *=* ]] || continue  # ARG NAME without a default sets nothing
    env_vars[${kv%%=*}]=${kv#*=}
  done
}

copy_into() {  # COPY [--chown=U:G] . DEST (the build context is the repository)
  local r=$1 args=$2 chown= src dest uid gid
  read -r -a words <<< "$args"
  if [[ ${words[0]} == --chown=* ]]; then chown=${words[0]#--chown=}; words=("${words[@]:1}"); fi
  [ "${#words[@]}" = 2 ] && [ "${words[0]}" = . ] \
    || { echo "container-smoke: only 'COPY [--chown=U:G] . DEST' is supported: '$args'" >&2; exit 1; }
  dest=${words[1]}; [[ $dest == /* ]] || dest=$workdir/$dest
  local excludes=()
  while read -r pat; do
    pat=${pat%%#*}; pat=${pat%"${pat##*[![:space:]]}"}; [ -n "$pat" ] || continue
    if [[ $pat == '**/'* ]]; then  # at any depth
      excludes+=(--no-anchored "--exclude=${pat#'**/'}" --anchored)
    else
      excludes+=("--exclude=./${pat#/}")
    fi
  done < "$repo/.dockerignore"
  local owner=()
  if [ -n "$chown" ]; then
    uid=$(uid_of "$r" "${chown%%:*}"); gid=$(gid_of "$r" "${chown%%:*}")
    owner=(--owner="$uid" --group="$gid" --numeric-owner)
  fi
  mkdir -p "$r$dest"
  tar -C "$repo" --anchored "${excludes[@]}" "${owner[@]}" -cf - . \
    | tar -C "$r$dest" --same-owner -xf -
}

# Follow instructions $2..$3 (indices) in root $1; RUN is executed only when $4 = run.
follow() {
  local r=$1 from=$2 to=$3 mode=$4 i line op rest
  for ((i = from; i <= to; i++)); do
    line=${instr[i]}; op=${line%% *}; rest=${line#* }
    case $op in
      FROM) ;;
      ARG|ENV) set_vars "$rest" ;;
      USER) user=$rest ;;
      WORKDIR) [[ $rest == /* ]] || rest=$workdir/$rest; workdir=$rest
               if [ "$mode" = run ]; then mkdir -p "$r$workdir"; fi ;;
      COPY) if [ "$mode" = run ]; then copy_into "$r" "$rest"; fi ;;
      RUN) if [ "$mode" = run ]; then
             log "RUN ${rest:0:100}"
             in_root "$r" "$rest" || { echo "container-smoke: failed: RUN $rest" >&2; exit 1; }
           fi ;;
      CMD) cmd=$rest ;;
      STOPSIGNAL) stopsignal=$rest ;;
      *) echo "container-smoke: instruction not supported: $op" >&2; exit 1 ;;
    esac
  done
}

# The layer up to the first COPY (apt, the user) is kept while its instructions stay the same.
deps=$root/deps
key=$(printf '%s\n' "${instr[@]:0:first_copy}" | sha256sum | cut -d' ' -f1)
if [ "$(cat "$deps/.layer-key" 2>/dev/null)" != "$key" ]; then
  log "building $deps (Dockerfile up to its first COPY)"
  rm -rf "$deps"; cp -a "$base" "$deps"
  mount_root "$deps"
  follow "$deps" 0 $((first_copy - 1)) run
  umount_all
  echo "$key" > "$deps/.layer-key"
else
  log "reusing $deps (Dockerfile unchanged up to its first COPY)"
  follow "$deps" 0 $((first_copy - 1)) state
fi
# The image: an overlay over deps (a copy where overlayfs is missing), remade on every call.
image=$root/image
log "building $image (COPY and what follows)"
rm -rf "$image" "$root/image-upper" "$root/image-work"
mkdir -p "$image" "$root/image-upper" "$root/image-work"
if mount -t overlay overlay \
    -o "lowerdir=$deps,upperdir=$root/image-upper,workdir=$root/image-work" "$image"; then
  mounted+=("$image")
else
  cp -a "$deps/." "$image"
fi
mount_root "$image"
follow "$image" "$first_copy" $((${#instr[@]} - 1)) run
log "image built: user $user, workdir $workdir, CMD $cmd, STOPSIGNAL $stopsignal"

# ---- 3. smoke tests as the image's user ---------------------------------------------------------
result=$root/smoke-result.md
since() { python3 -c "import sys, time; print(f'{time.time() - float(sys.argv[1]):.1f}')" "$1"; }
run_timed() {  # label, command: runs it in the image (log in ROOT/label.log), prints the wall time
  local t0
  t0=$(date +%s.%N)
  in_root "$image" "export PILEGROUP_PROGRESS=0; $2" > "$root/$1.log" 2>&1 \
    || { tail -30 "$root/$1.log" >&2; echo "container-smoke: failed: $2" >&2; exit 1; }
  since "$t0"
}
log "pilegroup --help"
run_timed help "pilegroup --help" > /dev/null
log "serial single_pile"
t_serial=$(run_timed serial "rm -rf out/smoke-serial && pilegroup run single_pile --out out/smoke-serial")
log "mpirun -n 2 single_pile"
t_mpi=$(run_timed mpi "rm -rf out/smoke-mpi && mpirun -n 2 pilegroup run single_pile --out out/smoke-mpi")
# What `docker stop` does to a 2-rank run: the image's STOPSIGNAL to mpirun (PID 1 in a
# container) once a checkpoint exists; the run must stop with it, exit 128 + the signal number
# and leave summary.json "interrupted".
log "docker stop ($stopsignal) to mpirun -n 2 single_pile"
sig=${stopsignal#SIG}
t_stop=$(run_timed stop "rm -rf out/smoke-stop; mpirun -n 2 pilegroup run single_pile \
  --out out/smoke-stop & pid=\$!; while [ ! -e out/smoke-stop/checkpoint/manifest.json ]; do \
  kill -0 \$pid || exit 1; sleep 0.2; done; kill -s $sig \$pid; wait \$pid; rc=\$?; \
  echo exit \$rc; [ \$rc = $((128 + $(kill -l "$sig"))) ] \
  && grep -q '\"status\": \"interrupted\"' out/smoke-stop/summary.json")
t_tests=-; tests_line=none; hypre_summary=-; t_hypre=-
case $tests in
  fast) log "make test"; t_tests=$(run_timed tests "make test"); tests_line="make test" ;;
  smoke) log "ruff and the smoke subset"
         t_tests=$(run_timed tests "make lint && .venv/bin/python -m pytest -m 'not slow' -q $(echo $SMOKE_TESTS)")
         tests_line="make lint; pytest -m 'not slow' $(echo $SMOKE_TESTS)" ;;
esac
tests_summary=$( [ "$tests" = none ] || grep -E '[0-9]+ (passed|failed)' "$root/tests.log" | tail -1)
# The hypre preset's tests (marker hypre; skipped where PETSc has no hypre, run here): part of
# `make test`, run on their own after the subset.
if [ "$tests" = smoke ]; then
  log "make test-hypre"
  t_hypre=$(run_timed hypre "make test-hypre")
  hypre_summary=$(grep -E '[0-9]+ (passed|failed)' "$root/hypre.log" | tail -1)
elif [ "$tests" = fast ]; then
  hypre_summary="in make test"
fi

# The cap settlement against a serial run in the repository's venv (PyPI's wheels).
venv_run=$root/venv-single-pile
t_venv=-
if [ -x "$repo/.venv/bin/pilegroup" ]; then
  log "serial single_pile in $repo/.venv"
  t0=$(date +%s.%N)
  rm -rf "$venv_run"
  (cd "$repo" && PILEGROUP_PROGRESS=0 .venv/bin/pilegroup run single_pile --out "$venv_run") \
    > "$root/venv.log" 2>&1 || { tail -30 "$root/venv.log" >&2; exit 1; }
  t_venv=$(since "$t0")
fi
compare=$(python3 - "$image$workdir/out/smoke-serial/settlement.csv" \
  "$image$workdir/out/smoke-mpi/settlement.csv" "$venv_run/settlement.csv" <<'PY'
import csv, sys
from pathlib import Path

def read(p):
    if not Path(p).exists():
        return None
    with open(p) as f:
        rows = list(csv.DictReader(f))
    key = next(k for k in rows[0] if k.startswith("settlement"))
    return [float(r[key]) for r in rows], rows[-1]["t_day"], key

serial, mpi, venv = (read(p) for p in sys.argv[1:])
print(f"| image, serial: {serial[2]} at t = {serial[1]} day | {serial[0][-1]:.10g} |")
print(f"| image, mpirun -n 2 | {mpi[0][-1]:.10g} |")
def diff(a, b):
    return max(abs(x - y) for x, y in zip(a[0], b[0], strict=True))
print(f"| largest difference, serial against mpirun -n 2 (every output time) | {diff(serial, mpi):.3g} m |")
if venv:
    print(f"| venv (PyPI's wheels), serial | {venv[0][-1]:.10g} |")
    print(f"| largest difference, image serial against venv serial (every output time) "
          f"| {diff(serial, venv):.3g} m |")
PY
)
versions=$(in_root "$image" "python3 -c 'import dolfinx, petsc4py, mpi4py, sys; print(\"Python\", sys.version.split()[0], \"| DOLFINx\", dolfinx.__version__, \"| petsc4py\", petsc4py.__version__, \"| mpi4py\", mpi4py.__version__)'; mpirun --version | head -1")
umount_all

{
  echo "Date: $(date -u +%Y-%m-%dT%H:%MZ); host: $(nproc) cores, $(uname -r); commit $(git -C "$repo" rev-parse --short HEAD)$(git -C "$repo" diff --quiet HEAD || echo ' (with changes)')."
  echo "Image: $(echo "$versions" | tr '\n' ' ')"
  echo
  echo "| step (as user \`$user\` in \`$workdir\`) | wall (s) |"
  echo "| --- | ---: |"
  echo "| \`pilegroup run single_pile\` | $t_serial |"
  echo "| \`mpirun -n 2 pilegroup run single_pile\` | $t_mpi |"
  echo "| \`docker stop\` ($stopsignal to \`mpirun\` after the first checkpoint): $(grep '^exit' "$root/stop.log"), summary \`interrupted\` | $t_stop |"
  echo "| tests: \`$tests_line\` ($tests_summary) | $t_tests |"
  echo "| the hypre preset's tests: \`make test-hypre\` ($hypre_summary) | $t_hypre |"
  echo "| the same serial run in the repository's .venv | $t_venv |"
  echo
  echo "| cap settlement at the last output time | m |"
  echo "| --- | ---: |"
  echo "$compare"
} | tee "$result"
log "summary in $result"
