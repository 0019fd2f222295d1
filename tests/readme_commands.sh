#!/usr/bin/env bash
# Every command README.md shows, run as written, in the README's order, from
# the repository root; stops at the first failure and says which.
# - ```bash / ```sh blocks: each line is a command (a trailing backslash
#   continues it; blank and comment lines are skipped), run by bash.
#   `bash tests/run.sh` is skipped: it is the test run that calls this script.
#   `bash demo/run.sh` runs as written (it builds the FMUs, the FMU binary of
#   `eigenmpc export` and the C library the later commands use).
# - ```python blocks: run by the project's .venv/bin/python (with fmpy, from
#   tests/python/requirements.txt; created as tests/run.sh does if missing).
# - ```c blocks: the README names the file it shows (the paragraph before it
#   ends in `FILE`:); the block must be that file, which a bash command
#   compiles.
# Outputs go under target/ (git-ignored); the run must leave `git status`
# with nothing new. Logs: target/readme-commands/. Usage: bash
# tests/readme_commands.sh (from anywhere; after the release build, as in
# tests/run.sh, so that `cargo run --release` finds it built).
set -euo pipefail
cd "$(dirname "$0")/.."

logs=target/readme-commands
rm -rf "$logs" && mkdir -p "$logs"
status_before=$(git status --porcelain --untracked-files=all | sort)

# The README's blocks, one file each in $logs, listed in order in
# $logs/steps as KIND<TAB>LINE<TAB>FILE.
python3 - "$logs" <<'PY'
import pathlib, re, sys

logs = pathlib.Path(sys.argv[1])
lines = pathlib.Path("README.md").read_text().splitlines()
steps, i, n = [], 0, 0
while i < len(lines):
    m = re.match(r"^```(\w*)\s*$", lines[i])
    if not m:
        i += 1
        continue
    lang, start = m.group(1), i + 1
    j = start
    while j < len(lines) and not lines[j].startswith("```"):
        j += 1
    body = lines[start:j]
    if lang in ("bash", "sh"):
        k = 0
        while k < len(body):
            first = k
            cmd = body[k]
            while cmd.endswith("\\") and k + 1 < len(body):
                k += 1
                cmd = cmd + "\n" + body[k]
            k += 1
            if not cmd.strip() or cmd.lstrip().startswith("#"):
                continue
            n += 1
            f = logs / f"{n:02d}.sh"
            f.write_text(cmd + "\n")
            steps.append(("bash", start + first + 1, f))
    elif lang == "python":
        n += 1
        f = logs / f"{n:02d}.py"
        f.write_text("\n".join(body) + "\n")
        steps.append(("python", start + 1, f))
    elif lang == "c":
        # The file the README says it shows: the last `path.c` before the block.
        before = " ".join(lines[max(0, start - 4):start - 1])
        named = re.findall(r"`([\w./-]+\.c)`", before)
        if not named:
            sys.exit(f"README.md:{start}: a C block must say which file it shows (`FILE.c`:)")
        shown = "\n".join(body) + "\n"
        if pathlib.Path(named[-1]).read_text() != shown:
            sys.exit(f"README.md:{start}: the C block is not {named[-1]}: copy one into the other")
        print(f"README.md:{start}: the C block is {named[-1]}")
    i = j + 1
with open(logs / "steps", "w") as out:
    for kind, line, f in steps:
        out.write(f"{kind}\t{line}\t{f}\n")
PY

python_env() {
    if ! .venv/bin/python -c "import fmpy" >/dev/null 2>&1; then
        echo "   (.venv with fmpy: creating it)"
        if [ ! -x .venv/bin/python ]; then
            if ! python3 -c "import ensurepip, venv" >/dev/null 2>&1; then
                source scripts/ensure-build-deps.sh
                apt_install python3-venv
            fi
            rm -rf .venv
            python3 -m venv .venv
        fi
        .venv/bin/pip install -q --disable-pip-version-check -r tests/python/requirements.txt
    fi
}

count=0
while IFS=$'\t' read -r kind line file; do
    cmd=$(cat "$file")
    log="${file%.*}.log"
    if [ "$kind" = bash ] && [ "$cmd" = "bash tests/run.sh" ]; then
        echo "== README.md:$line: $cmd: skipped (the test run that calls this script)"
        continue
    fi
    if [ "$kind" = python ]; then
        python_env
        echo "== README.md:$line: the python block (.venv/bin/python)"
        run=(.venv/bin/python "$file")
    else
        echo "== README.md:$line: $cmd"
        run=(bash -euo pipefail "$file")
    fi
    start=$SECONDS
    if ! "${run[@]}" >"$log" 2>&1; then
        tail -n 40 "$log" >&2
        echo "README.md:$line: this command failed (log: $log):" >&2
        echo "$cmd" >&2
        exit 1
    fi
    count=$((count + 1))
    echo "   ok in $((SECONDS - start)) s; last lines:"
    tail -n 3 "$log" | cut -c1-160 | sed 's/^/   | /'
done <"$logs/steps"

status_after=$(git status --porcelain --untracked-files=all | sort)
if new=$(comm -13 <(echo "$status_before") <(echo "$status_after")) && [ -n "$new" ]; then
    echo "the README's commands changed what git sees:" >&2
    echo "$new" >&2
    exit 1
fi
echo "all $count of README.md's commands ran as written (${SECONDS} s)"
