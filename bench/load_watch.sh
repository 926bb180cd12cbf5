# Sourced by the bench scripts: the largest 1-minute load average seen while a command runs.
#   peak=$(with_peak_load FILE command args...)   # runs the command, then prints the peak
# FILE holds the running peak; the command's own output goes where the caller sends it.
with_peak_load() {
  local peak=$1
  shift
  echo 0 > "$peak"
  (while :; do
     l=$(cut -d' ' -f1 /proc/loadavg)
     awk -v l="$l" -v p="$(cat "$peak")" 'BEGIN{exit !(l>p)}' && echo "$l" > "$peak"
     sleep 1
   done) &
  local watcher=$!
  "$@"
  local status=$?
  kill $watcher 2> /dev/null || true
  wait $watcher 2> /dev/null || true
  return $status
}
