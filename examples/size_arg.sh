# size_arg.sh - the command line of the generator scripts (chain.sh,
# chain_spatial.sh, scissor.sh, train.sh), sourced by them:
#
#   . "$(dirname "$0")/size_arg.sh"
#   size_arg "$@"          sets n to N (a positive integer), or exits 2
#   size_out               runs the script's gen into OUTFILE, or stdout
#
# A script called as `sh examples/X.sh N [OUTFILE]`. POSIX sh only.

size_usage() {
    echo "usage: sh $0 N [OUTFILE]   (N a positive integer)" >&2
    exit 2
}

size_arg() {
    [ $# -ge 1 ] && [ $# -le 2 ] || size_usage
    case $1 in
        ''|*[!0-9]*) size_usage ;;
    esac
    n=$1
    [ "$n" -ge 1 ] 2>/dev/null || size_usage
    size_file=${2:-}
}

size_out() {
    if [ -n "$size_file" ]; then
        gen > "$size_file" || exit 1
    else
        gen
    fi
}
