# Sourced by the bench/peers scripts, from the repository root. `peers_setup MODULES
# PACKAGE...` sets `bin`, the mbfmu executable as an absolute path ($MBFMU_BIN, else
# `cargo build --release`'s ${CARGO_TARGET_DIR:-target}/release/mbfmu), and `py`, the
# Python of bench/peers/.venv, after installing the PACKAGEs there unless `import
# MODULES` already works (bench-only dependencies, never test ones).
peers_setup() {
    local modules="$1"
    shift
    if [ -n "${MBFMU_BIN:-}" ]; then
        bin="$MBFMU_BIN"
    else
        cargo build --release --quiet
        bin="${CARGO_TARGET_DIR:-target}/release/mbfmu"
    fi
    bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
    local venv=bench/peers/.venv
    py="$venv/bin/python"
    if ! "$py" -c "import $modules" 2>/dev/null; then
        python3 -m venv "$venv"
        "$py" -m pip install --quiet --upgrade pip
        "$py" -m pip install --quiet "$@"
    fi
}
