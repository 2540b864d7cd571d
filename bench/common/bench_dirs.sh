# Sourced by the bench/run_*.sh scripts: the BUILD_DIR and OUT_DIR every one of them takes first.
#
#   bench_dirs EXACT EXTRA_USAGE "$@"
#
# EXACT: "exact" when nothing may follow the two directories, anything else to allow more arguments;
# EXTRA_USAGE: what the usage line shows after them. Sets BUILD (absolute) and OUT (created, absolute);
# exits with status 2 and the usage line on stderr when they are missing or unusable.
bench_dirs() {
    local exact=$1 extra=$2
    shift 2
    if [[ $# -lt 2 || ($exact == exact && $# -ne 2) ]]; then
        echo "usage: $0 BUILD_DIR OUT_DIR${extra:+ $extra}" >&2
        exit 2
    fi
    BUILD=$(cd "$1" && pwd) || { echo "$0: no build directory '$1'" >&2; exit 2; }
    mkdir -p "$2" || exit 2
    OUT=$(cd "$2" && pwd)
}
