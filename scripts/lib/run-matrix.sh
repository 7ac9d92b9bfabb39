# Sourced by the measurement scripts (scripts/ablation.sh, scripts/reconstruction-bench.sh): `bin` is the
# beslam binary of BESLAM_BUILD_DIR (default build; built when missing), python3 is there for the tables,
# and run_once DIR CONFIG [--set k=v]... runs one pipeline into DIR (log: DIR.log) unless DIR already
# holds a finished run (summary.json whose status is not failed), so a rerun picks up where it stopped
# (a failed or interrupted run is replaced: --overwrite).
bin="${BESLAM_BUILD_DIR:-build}/bin/beslam"
[ -x "$bin" ] || { scripts/install-deps.sh && scripts/build.sh; }
command -v python3 >/dev/null || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3; }

run_once() {
  local dir="$1" config="$2"; shift 2
  if [ -f "$dir/summary.json" ] && ! grep -q '"status": "failed\|"interrupted": true' "$dir/summary.json"; then return; fi
  mkdir -p "$(dirname "$dir")"
  echo "== $dir" >&2
  "$bin" run "$config" --out "$dir" --overwrite "$@" > "$dir.log" 2>&1 || { echo "failed: $dir (see $dir.log)" >&2; return 1; }
}
