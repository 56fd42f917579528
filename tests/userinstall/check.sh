#!/usr/bin/env bash
# The user-install check: palaestra installed as the README's "own environment" section says,
# in a fresh virtualenv, from a clone of the committed tree (an untracked file cannot help),
# with no gymnasium, no stable-baselines3 and no dev tools; then tests/userinstall/smoke.py in it.
# torch==2.13.0 stands in for the README's CPU-index line, which CI cannot reach.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
py="${PY:-python3}"
extras="train,box2d,mujoco,render,progress,sweep,ray"
work="$(mktemp -d "${TMPDIR:-/tmp}/palaestra-userinstall.XXXXXX")"
trap 'rm -rf "$work"' EXIT
start=$SECONDS

git clone --quiet --no-hardlinks "$root" "$work/palaestra"
echo "user-install check: commit $(git -C "$work/palaestra" rev-parse --short HEAD), extras [$extras]"
"$py" -m venv "$work/venv"
pip=("$work/venv/bin/python" -m pip --quiet --disable-pip-version-check)
# This workplace's pip.conf names local indexes that may be absent: pip warns per package.
exec 2> >(grep -v "^WARNING: Location 'file://" >&2)
"${pip[@]}" install torch==2.13.0
# README: the CPU torch first, then the extras; the extras must keep it (no CUDA wheels).
(cd "$work/palaestra" && "${pip[@]}" install --dry-run --report "$work/report.json" ".[$extras]" >/dev/null)
"$work/venv/bin/python" - "$work/report.json" <<'EOF'
import json, sys
names = [i["metadata"]["name"] for i in json.load(open(sys.argv[1]))["install"]]
if "torch" in [n.lower() for n in names]:
    sys.exit("the README's install would replace the CPU torch installed first")
cuda = [n for n in names if n.lower().startswith("nvidia-") or n.lower() == "triton"]
if cuda:
    sys.exit(f"the README's install would pull CUDA wheels: {cuda}")
print(f"dry run: {len(names)} packages, no nvidia-* wheel")
EOF
(cd "$work/palaestra" && "${pip[@]}" install ".[$extras]")
echo "installed in $((SECONDS - start)) s"
"$work/venv/bin/python" "$work/palaestra/tests/userinstall/smoke.py" "$work/user"
echo "user-install check: $((SECONDS - start)) s in all"
