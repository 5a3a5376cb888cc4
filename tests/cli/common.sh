# Shared by the command-line checks (sourced): fail MESSAGE ends the check; expect_error EXIT_CODE TEXT
# command... runs the command and fails unless it exits with EXIT_CODE and prints TEXT on stderr.
fail() { echo "$(basename "$0" .sh): FAILED: $*" >&2; exit 1; }
expect_error() {
  local code="$1" text="$2"
  shift 2
  "$@" >out.txt 2>err.txt
  local got=$?
  [ "$got" = "$code" ] || { cat err.txt; fail "'$*' exited $got, expected $code"; }
  grep -qF -- "$text" err.txt || { cat err.txt; fail "'$*' did not say: $text"; }
}
# start_in DIR: an empty DIR as the working folder, holding the built-in lift scene (lift.off/.sel/.def)
# made by $msdeform.
start_in() {
  rm -rf "$1"
  mkdir -p "$1"
  cd "$1" || exit 1
  "$msdeform" scene lift --resolution 2k -o . >/dev/null || fail "scene lift"
}
