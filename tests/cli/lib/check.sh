# What the command-line tests check with, sourced by them: a failure names what failed and shows
# the command's output.
fail() {
    echo "FAIL: $*" >&2
    exit 1
}
# expect_rc STATUS COMMAND...: run it (stdout to last.out, stderr to last.err), want STATUS.
expect_rc() {
    local want=$1 rc=0
    shift
    "$@" >last.out 2>last.err || rc=$?
    [ "$rc" -eq "$want" ] || { cat last.out last.err >&2; fail "'$*' exited $rc, expected $want"; }
}
# has FILE TEXT / lacks FILE TEXT: whether the file holds the text (fixed string).
has() { grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "$1 lacks: $2"; }; }
lacks() { ! grep -qF -- "$2" "$1" || { cat "$1" >&2; fail "$1 has: $2"; }; }
# work_in DIR: a test's own empty working directory, entered.
work_in() {
    rm -rf "$1"
    mkdir -p "$1"
    cd "$1"
}
