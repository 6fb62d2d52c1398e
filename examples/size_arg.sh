# size_arg.sh - the command line of the generator scripts (chain.sh,
# chain_spatial.sh, scissor.sh, train.sh, a02_four_bar.sh), sourced by them:
#
#   . "$(dirname "$0")/size_arg.sh"
#   size_arg A B "$@"      sets n to N (a positive integer whose
#                          A N + B coordinates mechc's default --max-coords,
#                          200000, admits), or exits 2
#   size_out               runs the script's gen into OUTFILE, or stdout
#
# A script called as `sh examples/X.sh N [OUTFILE]`. POSIX sh only.

size_max_coords=200000   # mechc's default --max-coords (generator/base/limits.h)

size_usage() {
    echo "usage: sh $0 N [OUTFILE]   (N a positive integer)" >&2
    exit 2
}

size_arg() {
    size_per=$1 size_base=$2
    shift 2
    [ $# -ge 1 ] && [ $# -le 2 ] || size_usage
    case $1 in
        ''|*[!0-9]*) size_usage ;;
    esac
    # N up to what mechc's default --max-coords admits: a larger one
    # would only write a file mechc refuses unless told otherwise (and for
    # N in the billions, write for hours). Files this large pass the
    # default --max-file-bytes (4 MB) already: mechc names that limit.
    size_top=$(( (size_max_coords - size_base) / size_per ))
    n=$(echo "$1" | sed 's/^0*//')
    if [ ${#n} -gt 9 ] || [ "${n:-0}" -gt "$size_top" ]; then
        echo "sh $0: N = $1 gives more than $size_max_coords coordinates (mechc's" \
             "default --max-coords): N is at most $size_top" >&2
        exit 2
    fi
    [ "${n:-0}" -ge 1 ] 2>/dev/null || size_usage
    size_file=${2:-}
}

size_out() {
    if [ -n "$size_file" ]; then
        gen > "$size_file" || exit 1
    else
        gen
    fi
}
