"""Where a looped pose's time goes, by function, inlined ones included: the samples of a
`perf record -e cpu-clock` run of bench/walk/single_pose.py, those in the core module put on
the innermost source function of each sample's address (addr2line -i; an AVX-512 intrinsic
on its caller, a lambda on the function it sits in), as shares of Embree's samples. The
module must carry its symbols and line tables (GIGASCROLL_KEEP_SYMBOLS), e.g.

    cmake -S . -B build/profile -G Ninja -DGIGASCROLL_KEEP_SYMBOLS=ON -DGIGASCROLL_TESTS=OFF \
        -DGIGASCROLL_BENCH=OFF -DPython_EXECUTABLE=.venv/bin/python3
    cmake --build build/profile --target _core
    perf record -e cpu-clock -F 4000 -o left.data .venv/bin/python bench/walk/single_pose.py \
        1800x1920 120 left --core build/profile/_core.cpython-311-x86_64-linux-gnu.so
    .venv/bin/python bench/walk/profile_functions.py left.data

Sampling on a timer, not on counters: a sample lands near, not always on, the instruction
that took the time, so the split is good to a few percent of the whole.
"""
import argparse
import collections
import os
import re
import subprocess
import sys


def fail(message):
    """One line on stderr and exit status 2, as the gigascroll commands do."""
    print(f"profile_functions: {message}", file=sys.stderr)
    sys.exit(2)


def run(*command):
    """A tool's standard output as lines; a missing tool or its failure ends the script."""
    try:
        return subprocess.run(command, capture_output=True, text=True,
                              check=True).stdout.splitlines()
    except FileNotFoundError:
        fail(f"{command[0]} is not installed (Debian: linux-perf, binutils)")
    except subprocess.CalledProcessError as e:
        last = (e.stderr or "").strip().splitlines()
        fail(f"{' '.join(command[:3])} failed: {last[-1] if last else e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", help="perf.data of the run")
    ap.add_argument("--module", help="the module the run loaded, if not the _core.* one perf "
                    "recorded (e.g. single_pose.py's --core)")
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    # One pass over the run: the module's mapping ([start, end) at file offset pgoff; it comes
    # before the samples that fall in it) and every sample's address and object.
    recorded, mapping, samples = None, None, []
    for line in run("perf", "script", "-i", a.data, "--show-mmap-events", "-F", "ip,dso"):
        m = re.search(r"MMAP2? .*\[(0x[0-9a-f]+)\((0x[0-9a-f]+)\) @ (0x[0-9a-f]+) .*\]: r-xp (\S+)$",
                      line)
        if m:
            if (os.path.realpath(m.group(4)) == os.path.realpath(a.module) if a.module
                    else os.path.basename(m.group(4)).startswith("_core.")):
                start, size, pgoff = (int(m.group(k), 16) for k in (1, 2, 3))
                recorded, mapping = m.group(4), (start, start + size, pgoff)
            continue
        p = line.split(None, 1)
        if len(p) == 2 and re.fullmatch(r"[0-9a-f]+", p[0]):
            samples.append((int(p[0], 16), p[1].strip("()")))
    if mapping is None:
        fail("the run did not load the core module")
    module = a.module or recorded
    # File offset to address in the file: the executable LOAD segment's vaddr - offset.
    segments = [l.split() for l in run("readelf", "-lW", module)
                if l.strip().startswith("LOAD") and " R E " in l]
    if len(segments) != 1:
        fail(f"{module}: not one executable segment")
    shift = int(segments[0][2], 16) - int(segments[0][1], 16)
    by_object, core = collections.Counter(), collections.Counter()
    for ip, obj in samples:
        if mapping[0] <= ip < mapping[1]:
            by_object["core"] += 1
            core[ip - mapping[0] + mapping[2] + shift] += 1
        else:
            by_object["embree" if "embree" in os.path.basename(obj) else "other"] += 1
    if not core:  # (addr2line without addresses would read them from the terminal)
        fail("no samples in the core module")
    addrs = sorted(core)
    out = run("addr2line", "-a", "-i", "-f", "-C", "-e", module, *(hex(x) for x in addrs))
    frames, current, i = {}, None, 0
    while i < len(out):
        if out[i].startswith("0x"):
            current = int(out[i], 16)
            frames[current] = []
            i += 1
            continue
        frames[current].append((out[i], out[i + 1]))
        i += 2
    functions = collections.Counter()
    for x in addrs:
        names = [re.sub(r"\(.*", "", f)[-60:] for f, loc in frames.get(x, [])
                 if not f.startswith("_mm") and "intrin" not in loc]
        # A lambda (operator()) is named by the function it sits in.
        owner = next((n for n in names if not n.endswith("operator")), "?")
        functions[names[0] if names and names[0] == owner else f"a lambda in {owner}"] += core[x]
    total = sum(by_object.values())
    print(f"{total} samples: core {by_object['core'] / total:.1%}, Embree "
          f"{by_object['embree'] / total:.1%}, other {by_object['other'] / total:.1%}")
    print("core samples by innermost function, as a share of Embree's:")
    for name, n in functions.most_common(a.top):
        print(f"  {n / max(1, by_object['embree']):6.1%}  {name}")


if __name__ == "__main__":
    main()
