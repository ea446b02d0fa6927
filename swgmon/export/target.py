"""Cortex-M4F measurements of the exported stage: flash, RAM and cycles per window.

**Size.** The image of the stage alone (:data:`.firmware.MAIN_SIZE`), built
with :data:`CFLAGS` and :data:`LDFLAGS`, measured by ``arm-none-eabi-size``: flash = text
+ data, RAM = data + bss + the stack high-water mark of a real window run under QEMU; an
empty ``main``'s image beside it (start-up alone).

**Cycles.** The bench image runs one held-out window under ``qemu-system-arm -M
mps2-an386`` one instruction per translation block; the instructions between the two
marker functions are counted and classified by mnemonic, each class given the
Cortex-M4's cycle counts (ARM Cortex-M4 Technical Reference Manual, r0p1, Table 3-1, and
the FPU's, Table 7-1): a low bound (every instruction at its fewest cycles) and a high
bound (at its most); no flash wait states, bus contention or interrupts. Method, limits
and figures: ``docs/EXPORT.md``, "Size and cycles (Cortex-M4F)".
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from swgmon.export import firmware

CROSS = "arm-none-eabi-gcc"
QEMU = "qemu-system-arm"
INSTALL = "sudo apt-get install -y gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
ARCH = ("-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16")
CFLAGS = (*ARCH, "-std=c99", "-Os", "-ffp-contract=off", "-ffunction-sections",
          "-fdata-sections", "-Wall")
LDFLAGS = ("-nostartfiles", "--specs=nano.specs", "-Wl,--gc-sections")
CLOCK_HZ = 168e6


def missing_tools() -> str | None:
    """Why the target can't be measured (a tool absent, with the install command), or
    None."""
    for tool in (CROSS, QEMU):
        if shutil.which(tool) is None:
            return f"{tool} not found: {INSTALL}"
    return None


class ToolError(RuntimeError):
    """A cross tool failed (non-zero exit, timeout, not executable); the message is one
    line naming the tool, its exit status and its first error line."""


def tool_message(name: str, rc: int | str, text: str) -> str:
    """One line on a failed tool: its name, exit status and first error line (else its
    last line), shortened to 200 characters."""
    lines = [" ".join(s.split()) for s in text.splitlines() if s.strip()]
    first = next((s for s in lines if "error" in s.lower()), lines[-1] if lines else "")
    first = first if len(first) <= 200 else first[:197] + "..."
    return f"{name} failed (exit {rc})" + (f": {first}" if first else "")


def _run(cmd: list[str], cwd: Path, timeout: float = 600) -> str:
    try:
        res = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise ToolError(f"{Path(cmd[0]).name} failed (no answer in {timeout:g} s)") from None
    except OSError as e:
        raise ToolError(f"{Path(cmd[0]).name} failed ({e.strerror or e})") from None
    if res.returncode:
        raise ToolError(tool_message(Path(cmd[0]).name, res.returncode,
                                     res.stderr or res.stdout))
    return res.stdout


def link(src: Path, work: Path, main: str, extra: dict[str, str], name: str) -> Path:
    """Compile and link an image of the stage in ``src`` with ``main`` (C source)."""
    (work / "startup.c").write_text(firmware.STARTUP)
    (work / "link.ld").write_text(firmware.LINK)
    (work / f"{name}.c").write_text(main)
    for k, v in extra.items():
        (work / k).write_text(v)
    elf = work / f"{name}.elf"
    files = [str(work / "startup.c"), str(work / f"{name}.c")]
    if "swg_monitor.h" in main:
        files.append(str(src / "swg_monitor.c"))
    _run([CROSS, *CFLAGS, "-I", str(src), "-I", str(work), *files, "-T",
          str(work / "link.ld"), *LDFLAGS, "-o", str(elf), "-lm"], work)
    return elf


def sizes(elf: Path) -> dict[str, int]:
    """``arm-none-eabi-size`` (Berkeley) of an image: text, data, bss."""
    out = _run(["arm-none-eabi-size", str(elf)], elf.parent).splitlines()[1].split()
    return {"text": int(out[0]), "data": int(out[1]), "bss": int(out[2])}


def _symbol(elf: Path, name: str) -> int:
    for line in _run(["arm-none-eabi-nm", str(elf)], elf.parent).splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name:
            return int(parts[0], 16) & ~1
    raise ToolError(f"arm-none-eabi-nm: {name} not in {elf.name}")


def _qemu(elf: Path, log: Path) -> str:
    cmd = [QEMU, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
           "-serial", "null", "-semihosting-config", "enable=on,target=native",
           "-singlestep", "-d", "in_asm,exec,nochain", "-D", str(log), "-kernel", str(elf)]
    try:
        res = subprocess.run(cmd, cwd=elf.parent, capture_output=True, text=True,
                             timeout=900, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise ToolError(f"{QEMU} failed (no answer in 900 s)") from None
    except OSError as e:
        raise ToolError(f"{QEMU} failed ({e.strerror or e})") from None
    text = res.stdout + res.stderr  # semihosting writes to stderr when it is not a tty
    line = next((s for s in text.splitlines() if s.startswith("class ")), None)
    if res.returncode or line is None:
        raise ToolError(tool_message(QEMU, res.returncode, text or "printed no result"))
    return line


_INSN = re.compile(r"^0x([0-9a-f]+):\s+(?:[0-9a-f]{4}\s?)+\s+(\S+)\s*(.*)$")
_EXEC = re.compile(r"\[[0-9a-f]+/([0-9a-f]+)/")


def trace(log: Path, begin: int, end: int) -> tuple[dict[int, tuple[str, str]], dict[int, int]]:
    """Disassembly by address and execution counts by address between the markers."""
    dis: dict[int, tuple[str, str]] = {}
    counts: dict[int, int] = {}
    inside = False
    with open(log, errors="replace") as fh:
        for line in fh:
            if line.startswith("0x"):
                m = _INSN.match(line.strip())
                if m:
                    dis[int(m.group(1), 16)] = (m.group(2), m.group(3))
                continue
            m = _EXEC.search(line) if line.startswith("Trace") else None
            if not m:
                continue
            pc = int(m.group(1), 16)
            if pc == begin:
                inside = True
            elif pc == end:
                inside = False
            if inside:
                counts[pc] = counts.get(pc, 0) + 1
    return dis, counts


def _regs(ops: str) -> int:
    inner = ops[ops.find("{") + 1:ops.find("}")] if "{" in ops else ""
    n = 0
    for part in filter(None, (s.strip() for s in inner.split(","))):
        words = 2 if part.startswith("d") else 1  # a D register moves two words
        if "-" in part:
            a, b = (int(re.sub(r"\D", "", s) or 0) for s in part.split("-"))
            n += (b - a + 1) * words
        else:
            n += words
    return max(n, 1)


_COND = "eq|ne|cs|cc|hs|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al"
_BRANCH = re.compile(rf"^(b|bl|blx|bx)({_COND})?$|^(cbz|cbnz|tbb|tbh)$")
_FIXED = {"vdiv": (14, 14), "vsqrt": (14, 14), "ldrd": (2, 3), "strd": (2, 3),
          "sdiv": (2, 12), "udiv": (2, 12), "vldr": (2, 2), "vstr": (2, 2),
          **dict.fromkeys(("vmla", "vmls", "vnmla", "vnmls", "vfma", "vfms", "vfnma",
                           "vfnms"), (3, 3))}
_MULTI = ("vldm", "vstm", "vpush", "vpop", "push", "pop", "ldm", "stm")


def _base(m: str) -> str:
    """A mnemonic without its size suffix and, for a conditional core instruction in an
    IT block, its condition (``moveq`` -> ``mov``; FPU mnemonics are kept whole)."""
    m = m.lower().split(".")[0]
    if m.startswith("v") or _BRANCH.match(m) or m in _FIXED:
        return m
    for prefix in ("ldr", "str", *_MULTI):
        if m.startswith(prefix):
            return m
    return re.sub(rf"({_COND})$", "", m) if len(m) > 3 else m


def cycle_range(mnemonic: str, ops: str) -> tuple[int, int]:
    """(fewest, most) Cortex-M4 cycles of one instruction (module docstring)."""
    m = _base(mnemonic)
    if m in _FIXED:
        return _FIXED[m]
    if m.startswith(_MULTI):
        n = _regs(ops)
        pc = 3 if m.startswith(("pop", "ldm")) and "pc" in ops else 0
        return 1 + n + (1 if pc else 0), 1 + n + pc
    if m.startswith(("ldr", "str")):
        return 1, 2
    if _BRANCH.match(m):
        return (2, 4) if m in ("bl", "blx") else (1, 4)
    return 1, 1


def count_cycles(log: Path, elf: Path) -> dict:
    """Instructions and the cycle range of the window between the markers."""
    dis, counts = trace(log, _symbol(elf, "swg_mark_begin"), _symbol(elf, "swg_mark_end"))
    lo = hi = n = unknown = 0
    for pc, k in counts.items():
        n += k
        if pc not in dis:
            unknown += k
            a, b = 1, 4
        else:
            a, b = cycle_range(*dis[pc])
        lo += a * k
        hi += b * k
    return {"instructions": n, "cycles_low": lo, "cycles_high": hi,
            "instructions_undecoded": unknown}


def measure(src: Path, x: np.ndarray, phi: np.ndarray, op: int, efficiency: float,
            clock_hz: float = CLOCK_HZ) -> dict:
    """Flash, RAM and cycles of the stage in ``src`` on one window (module docstring).

    Parameters
    ----------
    src : Path
        Folder of the exported C files.
    x : ndarray, shape (5, n_t)
        One window's bridge outputs [mV/V].
    phi : ndarray, shape (n_t,)
        Its input angle [rad].
    op : int
    efficiency : float
    clock_hz : float
        Core clock for the time per window [Hz].

    Returns
    -------
    dict
        Sizes, cycle range, the target's class, P(healthy) and feature bits (hex), and
        the methods in words.

    Raises
    ------
    ToolError
        If a tool is missing or fails (one line naming it).
    """
    why = missing_tools()
    if why:
        raise ToolError(why)
    with tempfile.TemporaryDirectory(prefix="swg_m4_") as tmp:
        work = Path(tmp)
        stage = sizes(link(src, work, firmware.MAIN_SIZE, {}, "size"))
        empty = sizes(link(src, work, firmware.MAIN_EMPTY, {}, "empty"))
        elf = link(src, work, firmware.MAIN_BENCH,
                   {"window.h": firmware.window_header(x, phi, op, efficiency)}, "bench")
        out = _qemu(elf, work / "trace.log")
        cyc = count_cycles(work / "trace.log", elf)
    words = out.split()
    stack = int(words[3], 16)
    return {**{f"image_{k}": v for k, v in stage.items()},
            **{f"startup_only_{k}": v for k, v in empty.items()},
            "flash_bytes": stage["text"] + stage["data"],
            "ram_bytes": stage["data"] + stage["bss"] + stack, "stack_bytes": stack,
            **cyc, "cycles_per_window": cyc["cycles_high"],
            "ms_per_window_at_168mhz": cyc["cycles_high"] / clock_hz * 1e3,
            "target_class": int(words[1], 16) - (1 << 32 if int(words[1], 16) >> 31 else 0),
            "target_p_healthy_bits": words[5], "target_feature_bits": words[7:],
            "compiler": _run([CROSS, "--version"], Path.cwd()).splitlines()[0],
            "cflags": " ".join(CFLAGS), "method_size": "arm-none-eabi-size of the stage "
            "image (flash = text + data; RAM = data + bss + stack high-water mark)",
            "method_cycles": "QEMU mps2-an386 instruction trace between markers, each "
            "instruction given its Cortex-M4 cycle range (TRM tables 3-1, 7-1); "
            "cycles_per_window = the high bound; no flash wait states modelled"}
