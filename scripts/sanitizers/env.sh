# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: how the sanitizers report (stack traces,
# abort on the first finding, the leak suppressions next to this file).
_san_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$_san_dir/lsan.supp:print_suppressions=0}
unset _san_dir
