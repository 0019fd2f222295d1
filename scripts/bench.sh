#!/usr/bin/env bash
# Regenerates docs/speed.md (the book's speed chapter, docs/book/src/performance.md, includes it): the per-sample times of
# `bench_mpc` with the CPU they were measured on and same-run ratios (the
# robots of robots/ first), the instruction counts per RTI sample
# (callgrind), which do not depend on the machine, and the first sample's
# start-up on the laboratory robots (examples/startup.rs). `bash scripts/bench.sh [OUT]` (default docs/speed.md); installs
# valgrind with apt when it is missing and you are root.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/speed.md}
source scripts/ensure-build-deps.sh
if ! command -v valgrind >/dev/null 2>&1; then
    apt_install valgrind
fi
cargo build --release --bin bench_mpc --example rti_profile --example startup
target_dir=${CARGO_TARGET_DIR:-target}
profile="$target_dir/release/examples/rti_profile"
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
cores=$(nproc)
mhz=$(grep -m1 'cpu MHz' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//' || true)
flags=$(grep -m1 '^flags' /proc/cpuinfo | tr ' ' '\n' | grep -E '^(avx2|fma|avx512f)$' | tr '\n' ' ' || true)

# Instructions of Controller::step, of its linearisation and of its QP solve
# per sample: each counted alone (callgrind collecting only inside the
# function), two run lengths subtracted so that the first sample (converged
# SQP from a cold start) drops out.
total() { # function-pattern start seconds qp variant -> instructions
    local file
    file=$(mktemp)
    valgrind --tool=callgrind --callgrind-out-file="$file" \
        --toggle-collect="$1" "$profile" "${@:2}" >/dev/null 2>&1
    callgrind_annotate "$file" 2>/dev/null | awk '
        /PROGRAM TOTALS/ { gsub(",", "", $1); print $1; exit }'
    rm -f "$file"
}
count() { # start seconds qp variant [robot energy tau_max] -> "step linearise qp"
    echo "$(total '*Controller<S,_,_>::step' "$@") \
$(total '*Controller<S,_,_>>::linearise' "$@") \
$(total '*QpSolver*::solve_stages' "$@")"
}
per_sample() { # start qp variant [robot energy tau_max]
    local a b
    a=($(count "$1" 10 "${@:2}"))
    b=($(count "$1" 20 "${@:2}"))
    # 400 samples between 10 s and 20 s at 25 ms.
    awk -v s1="${a[0]}" -v s2="${b[0]}" -v l1="${a[1]}" -v l2="${b[1]}" \
        -v q1="${a[2]}" -v q2="${b[2]}" 'BEGIN {
        printf "%.0f | %.0f | %.0f", (s2 - s1) / 400 / 1000, (l2 - l1) / 400 / 1000, (q2 - q1) / 400 / 1000 }'
}

{
    echo "# Speed of the EigenMPC control step"
    echo
    echo "Regenerate: \`bash scripts/bench.sh\` (this file). Measured on **${cpu}** (${cores} cores${mhz:+, ${mhz} MHz}; ${flags:-no AVX2/FMA}), $(rustc --version), release build, default target (x86-64 baseline, no \`target-cpu\`), $(date -u +%Y-%m-%d)."
    echo
    echo "## Instructions per sample (callgrind; the same on every x86-64 machine for this build)"
    echo
    echo "Paper set-up (N = 80, dt = 25 ms, 2 links), thousands of instructions per RTI sample, averaged over the 400 samples from 10 s to 20 s. \`rest\`: the paper's start at q = (0.05, 0.05), so 10-20 s is the torque-limited climb (saturated torques: active bounds in most QPs); \`orbit\`: from the 14 J in-phase eigenmode's turning point, on the orbit throughout (the steady state)."
    echo
    echo "| start | variant | QP | step (k instr.) | linearisation (k instr.) | QP solve (k instr.) |"
    echo "|---|---|---|---|---|---|"
    for start in orbit rest; do
        for variant in curved straight; do
            echo "| $start | $variant | riccati | $(per_sample $start riccati $variant) |"
        done
    done
    echo "| orbit | curved | clarabel | $(per_sample orbit clarabel curved) |"
    echo
    echo "The robots of the table below (curved, riccati, from every joint at 0.05 rad at rest, the controller \`eigenmpc simulate --model FILE\` builds), thousands of instructions per sample from 10 s to 20 s (the friction robots on their orbit by then; the paper's pendulum and the 3 point masses, at 14 J, still in the torque-limited climb):"
    echo
    echo "| robot | E_ref J | step (k instr.) | linearisation (k instr.) | QP solve (k instr.) | step / paper's |"
    echo "|---|---|---|---|---|---|"
    paper_step=""
    while read -r robot energy tau_max; do
        cells=$(per_sample rest riccati curved "$robot" "$energy" "$tau_max")
        step=${cells%% *}
        # The first robot is the paper's pendulum.
        paper_step=${paper_step:-$step}
        ratio=$(awk -v s="$step" -v p="$paper_step" 'BEGIN { printf "%.2f", s / p }')
        echo "| $(basename "$robot") | $energy | $cells | $ratio |"
    done < <("$target_dir/release/bench_mpc" --list-robots)
    echo
    "$target_dir/release/bench_mpc"
    echo
    echo "## The first sample"
    echo
    echo "The first sample starts from a zero-torque guess. \`Startup::Iterations(n)\` (the default: 10) takes n full Gauss-Newton iterations in it, one linearisation and one QP each: bounded work. \`Startup::Converge\` is the paper's converged SQP with its L1-merit line search (at most 30 iterations): on the laboratory robots it takes tens of milliseconds, with many step halvings (with their exact Coulomb law, before the prediction model smoothed it for three substeps, it never converged and took 90-180 ms). Curved, riccati, N = 80, 30 s from every joint at 0.05 rad at rest, the controller \`eigenmpc simulate --model FILE\` builds (\`cargo run --release --example startup\`); times on the machine above:"
    echo
    "$target_dir/release/examples/startup"
} > "$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out"
