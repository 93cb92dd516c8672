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


def perf_script(data, *args):
    return subprocess.run(["perf", "script", "-i", data, *args], capture_output=True, text=True,
                          check=True).stdout.splitlines()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", help="perf.data of the run")
    ap.add_argument("--module", help="the module the run loaded, if not the _core.* one perf "
                    "recorded (e.g. single_pose.py's --core)")
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    # Where the module's code was mapped: [start, end) at file offset pgoff.
    recorded, mapping = None, None
    for line in perf_script(a.data, "--show-mmap-events", "-F", "ip"):
        m = re.search(r"MMAP2? .*\[(0x[0-9a-f]+)\((0x[0-9a-f]+)\) @ (0x[0-9a-f]+) .*\]: r-xp (\S+)$",
                      line)
        if m and (os.path.realpath(m.group(4)) == os.path.realpath(a.module) if a.module
                  else os.path.basename(m.group(4)).startswith("_core.")):
            start, size, pgoff = (int(m.group(k), 16) for k in (1, 2, 3))
            recorded, mapping = m.group(4), (start, start + size, pgoff)
    if mapping is None:
        raise SystemExit("profile_functions: the run did not load the core module")
    module = a.module or recorded
    # File offset to address in the file: the executable LOAD segment's vaddr - offset.
    segments = [l.split() for l in subprocess.run(["readelf", "-lW", module], capture_output=True,
                                                   text=True, check=True).stdout.splitlines()
                if l.strip().startswith("LOAD") and " R E " in l]
    if len(segments) != 1:
        raise SystemExit(f"profile_functions: {module}: not one executable segment")
    shift = int(segments[0][2], 16) - int(segments[0][1], 16)
    by_object, core = collections.Counter(), collections.Counter()
    for line in perf_script(a.data, "-F", "ip,dso"):
        p = line.split(None, 1)
        if len(p) != 2:
            continue
        ip, obj = int(p[0], 16), p[1].strip("()")
        if mapping[0] <= ip < mapping[1]:
            by_object["core"] += 1
            core[ip - mapping[0] + mapping[2] + shift] += 1
        else:
            by_object["embree" if "embree" in os.path.basename(obj) else "other"] += 1
    addrs = sorted(core)
    out = subprocess.run(["addr2line", "-a", "-i", "-f", "-C", "-e", module] + [hex(x) for x in addrs],
                         capture_output=True, text=True, check=True).stdout.splitlines()
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
