"""The exported controller on a Cortex-M4F: cross-compiled with ``arm-none-eabi-gcc`` (newlib),
sized with ``arm-none-eabi-size``, and run on QEMU's Cortex-M4 board model (``mps2-an386``) to
count the instructions of one control step (docs/guide/export.md, "Cost on the target").

The project writes its own bare-metal frame: a vector table and reset handler (copy .data, clear
.bss, enable the FPU through CPACR, call ``main``, leave through semihosting), a linker script for
the board's memory (4 MB code SRAM at 0x00000000, 4 MB data SRAM at 0x20000000), and a
measuring ``main`` that prints ``key value`` lines through semihosting (SYS_WRITE0).

Counting method. QEMU 7.2 as Debian ships it has no TCG plugins; ``-icount shift=0`` makes its
virtual clock advance exactly 2^0 = 1 ns per executed instruction, and the board clocks the
core's SysTick (processor clock source) at 25 MHz, so one SysTick tick is 40 instructions. The
measuring loop runs the step over N samples twice, once calling it and once not (same code, the
call behind a flag read from a volatile), reading SysTick after every sample (24-bit differences
summed, so the total is exact to one tick at either end); the instructions of one step are
(ticks with - ticks without) * 40 / N, exact to 2 ticks * 40 / N. They include the call itself
(its arguments and the ``bl``). ``known_loop_instructions`` runs the same measurement on an
assembler loop whose count is read from its disassembly (tests/test_export_target.py).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from acdrive.errors import InputError

INSTALL_SCRIPT = "scripts/install-cross-tools.sh"
#: the issue's target flags (Cortex-M4F, single-precision FPU, hard-float ABI), C99 as the
#: host build (ISO C mode: no fused multiply-add contraction, as the float SIL build)
M4_FLAGS = ("-mcpu=cortex-m4", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-mthumb", "-O2",
            "-std=c99")  # fmt: skip
BOARD = "mps2-an386"
#: QEMU's MPS2 boards run the CPU (and SysTick's processor clock) at 25 MHz (hw/arm/mps2.c)
BOARD_CLOCK_HZ = 25_000_000
#: -icount shift=0: 1 ns of virtual time per instruction; one 25 MHz tick is 40 ns
INSTRUCTIONS_PER_TICK = 1_000_000_000 // BOARD_CLOCK_HZ
QEMU_ARGS = ("-M", BOARD, "-cpu", "cortex-m4", "-nographic", "-monitor", "none", "-serial",
             "none", "-semihosting-config", "enable=on,target=native",
             "-icount", "shift=0,align=off,sleep=off")  # fmt: skip
#: tools and what each is for (the one-line error names the tool and the script)
TOOLS = {
    "arm-none-eabi-gcc": "cross-compiling the controller for the Cortex-M4F",
    "arm-none-eabi-size": "the code and data size of the controller",
    "arm-none-eabi-objdump": "the disassembly the counting method is checked against",
    "qemu-system-arm": "running the controller on the Cortex-M4 board model",
}

STARTUP_C = r"""/* Bare-metal frame for QEMU's mps2-an386 (Cortex-M4F), written by acdrive.export._target:
   vector table, reset handler, semihosting output and exit, SysTick as a free-running timer. */
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);
void acd_reset_handler(void);

static void acd_fault(void)
{
    for (;;) {
    }
}

__attribute__((section(".vectors"), used)) static const void *const acd_vectors[16] = {
    &_estack, (void *)acd_reset_handler, (void *)acd_fault, (void *)acd_fault,
    (void *)acd_fault, (void *)acd_fault, (void *)acd_fault, 0, 0, 0, 0, (void *)acd_fault,
    (void *)acd_fault, 0, (void *)acd_fault, (void *)acd_fault};

/* Arm semihosting: operation in r0, argument in r1, BKPT 0xAB (Thumb) */
static int acd_semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

/* prints "key value\n" (SYS_WRITE0) */
void acd_report(const char *key, uint32_t value)
{
    char line[64], digits[12];
    int n = 0, k = 0;
    while (key[k] != 0 && n < 48) {
        line[n++] = key[k++];
    }
    line[n++] = ' ';
    k = 0;
    do {
        digits[k++] = (char)('0' + value % 10u);
        value /= 10u;
    } while (value != 0u);
    while (k > 0) {
        line[n++] = digits[--k];
    }
    line[n++] = '\n';
    line[n] = 0;
    (void)acd_semihost(0x04, line);
}

#define ACD_SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define ACD_SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define ACD_SYST_CVR (*(volatile uint32_t *)0xE000E018u)

/* SysTick free-running from 0xFFFFFF down, processor clock, no interrupt */
void acd_timer_start(void)
{
    ACD_SYST_RVR = 0xFFFFFFu;
    ACD_SYST_CVR = 0u;
    ACD_SYST_CSR = 5u;
}

uint32_t acd_timer(void)
{
    return ACD_SYST_CVR;
}

void acd_reset_handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) {
        *dst++ = *src++;
    }
    for (dst = &_sbss; dst < &_ebss;) {
        *dst++ = 0u;
    }
    *(volatile uint32_t *)0xE000ED88u |= (0xFu << 20); /* CPACR: CP10, CP11 full access */
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    if (main() == 0) {
        (void)acd_semihost(0x18, (const void *)0x20026u); /* SYS_EXIT, ApplicationExit */
    }
    (void)acd_semihost(0x18, (const void *)0x20023u); /* SYS_EXIT, RunTimeErrorUnknown */
    for (;;) {
    }
}
"""

LINKER_SCRIPT = """/* mps2-an386 memory map (QEMU): code SRAM at 0, data SRAM at 0x20000000 (acdrive) */
MEMORY
{
    FLASH (rx) : ORIGIN = 0x00000000, LENGTH = 4M
    RAM (rwx) : ORIGIN = 0x20000000, LENGTH = 4M
}
ENTRY(acd_reset_handler)
SECTIONS
{
    .text : { KEEP(*(.vectors)) *(.text*) *(.rodata*) . = ALIGN(4); } > FLASH
    .ARM.exidx : { *(.ARM.exidx*) } > FLASH
    .acd_replay : { KEEP(*(.acd_replay)) } > FLASH /* the measurement's inputs, not code */
    _sidata = LOADADDR(.data);
    .data : { _sdata = .; *(.data*) . = ALIGN(4); _edata = .; } > RAM AT > FLASH
    .bss (NOLOAD) : { _sbss = .; *(.bss*) *(COMMON) . = ALIGN(4); _ebss = .; end = .; } > RAM
    _estack = ORIGIN(RAM) + LENGTH(RAM);
}
"""

#: the measuring loop: {decls} declares what {call} needs, {setup} runs before each pass
MEASURE_C = r"""/* Instructions of one step on the board model, written by acdrive.export._target */
#include <stdint.h>
{include}
#define ACD_SAMPLES {samples}u

void acd_report(const char *key, uint32_t value);
void acd_timer_start(void);
uint32_t acd_timer(void);

{decls}
static volatile int acd_call_step;
static uint32_t acd_window_max, acd_window_min;

/* SysTick ticks over the ACD_SAMPLES samples, the step called if acd_call_step is set */
static uint32_t acd_pass(void)
{{
    const int call = acd_call_step;
    uint32_t k, sum = 0u, before, after, previous, window;
    {setup}
    previous = acd_timer();
    for (k = 0u; k < ACD_SAMPLES; ++k) {{
        before = acd_timer();
        if (call) {{
            {call}
        }}
        after = acd_timer();
        window = (before - after) & 0xFFFFFFu; /* both passes: the same code around the call */
        acd_window_max = window > acd_window_max ? window : acd_window_max;
        acd_window_min = window < acd_window_min ? window : acd_window_min;
        sum += (previous - after) & 0xFFFFFFu;
        previous = after;
    }}
    return sum;
}}

int main(void)
{{
    uint32_t without, with;
    acd_timer_start();
    acd_call_step = 0;
    without = acd_pass();
    acd_window_max = 0u; /* the windows of the pass that calls the step */
    acd_window_min = 0xFFFFFFFFu;
    acd_call_step = 1;
    with = acd_pass();
    acd_report("samples", ACD_SAMPLES);
    acd_report("ticks_without", without);
    acd_report("ticks_with", with);
    acd_report("window_max", acd_window_max);
    acd_report("window_min", acd_window_min);
    return 0;
}}
"""


def find_cross_tools() -> dict[str, str]:
    """The path of each cross tool; a missing one: one line naming it and the script."""
    paths = {}
    for tool, purpose in TOOLS.items():
        path = shutil.which(tool)
        if path is None:
            raise InputError(
                tool, f"was not found on PATH ({purpose}): {INSTALL_SCRIPT} installs it"
            )
        paths[tool] = path
    return paths


def _run(command: list[str], what: str, timeout: float = 300.0, stderr: bool = False) -> str:
    """stdout of ``command`` (with its stderr appended if ``stderr``: QEMU writes semihosting
    output there with -nographic)."""
    done = subprocess.run(command, capture_output=True, text=True, check=False, timeout=timeout)
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or done.stdout.strip().splitlines()
                 or ["(no message)"])[0]  # fmt: skip
        raise RuntimeError(f"{what} failed ({Path(command[0]).name}): {first}")
    return done.stdout + (done.stderr if stderr else "")


def compile_object(source: Path, obj: Path, tools: dict, defines=("ACDRIVE_FLOAT",)) -> Path:
    flags = [*M4_FLAGS, *(f"-D{d}" for d in defines)]
    _run([tools["arm-none-eabi-gcc"], *flags, "-c", str(source), "-o", str(obj)],
         f"cross-compiling {source.name}")  # fmt: skip
    return obj


def link(objects: list[Path], elf: Path, folder: Path, tools: dict) -> Path:
    (folder / "startup.c").write_text(STARTUP_C)
    (folder / "board.ld").write_text(LINKER_SCRIPT)
    startup = compile_object(folder / "startup.c", folder / "startup.o", tools, defines=())
    _run([tools["arm-none-eabi-gcc"], *M4_FLAGS, "-nostartfiles", "-T", str(folder / "board.ld"),
          "--specs=nano.specs", str(startup), *map(str, objects), "-o", str(elf),
          "-lm", "-lc", "-lnosys"], f"linking {elf.name}")  # fmt: skip
    return elf


def sizes(path: Path, tools: dict) -> dict[str, int]:
    """text, data and bss bytes of an object or image (``arm-none-eabi-size``, Berkeley)."""
    out = _run([tools["arm-none-eabi-size"], "-B", str(path)], f"sizing {path.name}")
    text, data, bss = (int(x) for x in out.strip().splitlines()[-1].split()[:3])
    return {"text": text, "data": data, "bss": bss}


def image_sizes(elf: Path, tools: dict) -> dict[str, int]:
    """Bytes of a linked image by what they are (``arm-none-eabi-size -A``): code and constants
    (``.text``, ``.ARM.exidx``: the controller, libm, libc, the frame), initialised and zeroed
    RAM; the replayed inputs (``.acd_replay``) are left out."""
    out = _run([tools["arm-none-eabi-size"], "-A", str(elf)], f"sizing {elf.name}")
    section = {}
    for line in out.splitlines():
        fields = line.split()
        if len(fields) == 3 and fields[0].startswith(".") and fields[1].isdigit():
            section[fields[0]] = int(fields[1])
    return {
        "text": section.get(".text", 0) + section.get(".ARM.exidx", 0),
        "data": section.get(".data", 0),
        "bss": section.get(".bss", 0),
    }


def symbol_sizes(obj: Path, tools: dict) -> dict[str, int]:
    """Bytes of each function of an object (from its disassembly's symbol table)."""
    objdump = tools["arm-none-eabi-objdump"]
    out = _run([objdump, "-t", str(obj)], f"reading the symbols of {obj.name}")
    found = {}
    for line in out.splitlines():
        fields = line.split()
        if len(fields) >= 6 and "F" in fields[1:3] and fields[-3].startswith(".text"):
            found[fields[-1]] = int(fields[-2], 16)
    return found


def run_on_board(elf: Path, tools: dict, timeout: float = 300.0) -> dict[str, int]:
    """Run ``elf`` on the board model; the ``key value`` lines it printed."""
    out = _run([tools["qemu-system-arm"], *QEMU_ARGS, "-kernel", str(elf)],
               f"running {elf.name} on {BOARD}", timeout, stderr=True)  # fmt: skip
    values = {}
    for line in out.splitlines():
        match = re.fullmatch(r"([a-z_]+) (\d+)", line.strip())
        if match:
            values[match.group(1)] = int(match.group(2))
    missing = {"samples", "ticks_with", "ticks_without"} - set(values)
    if missing:
        raise RuntimeError(f"{elf.name} on {BOARD} printed no {', '.join(sorted(missing))}")
    return values


def instructions_per_step(values: dict[str, int]) -> dict[str, float]:
    """From the measuring loop's lines: the mean instructions of one step (the call included),
    its resolution, and the longest and shortest single step (one timer window: the step, the
    call and a timer read, to one tick)."""
    n = values["samples"]
    ticks = values["ticks_with"] - values["ticks_without"]
    return {
        "samples": n,
        "instructions_per_step": ticks * INSTRUCTIONS_PER_TICK / n,
        "resolution": 2 * INSTRUCTIONS_PER_TICK / n,
        "longest_step_window": values["window_max"] * INSTRUCTIONS_PER_TICK,
        "shortest_step_window": values["window_min"] * INSTRUCTIONS_PER_TICK,
        "window_resolution": INSTRUCTIONS_PER_TICK,
    }


def measure_source(include: str, decls: str, setup: str, call: str, samples: int) -> str:
    return MEASURE_C.format(include=include, decls=decls, setup=setup, call=call,
                            samples=int(samples))  # fmt: skip


def known_loop_instructions(iterations: int, folder: Path, samples: int = 1000) -> dict:
    """The counting method on a loop of known length: ``acd_known_loop`` (Thumb-2 assembler:
    ``movw r0, #iterations``, then ``subs``/``bne`` per iteration, ``bx lr``) measured by the
    same loop as a controller step. Returns the measured counts and the function's instruction
    mnemonics read back from its disassembly."""
    if not (isinstance(iterations, int) and 1 <= iterations <= 65535):
        raise InputError("iterations", "must be an integer in 1..65535 (movw's immediate)")
    tools = find_cross_tools()
    folder = Path(folder)
    (folder / "known_loop.s").write_text(
        "    .syntax unified\n    .thumb\n    .text\n    .global acd_known_loop\n"
        "    .type acd_known_loop, %function\nacd_known_loop:\n"
        f"    movw r0, #{iterations}\n1:\n    subs r0, r0, #1\n    bne 1b\n    bx lr\n"
        "    .size acd_known_loop, . - acd_known_loop\n"
    )
    loop = compile_object(folder / "known_loop.s", folder / "known_loop.o", tools, defines=())
    (folder / "measure.c").write_text(
        measure_source("", "void acd_known_loop(void);", "", "acd_known_loop();", samples)
    )
    measure = compile_object(folder / "measure.c", folder / "measure.o", tools, defines=())
    elf = link([measure, loop], folder / "known_loop.elf", folder, tools)
    disassembly = _run([tools["arm-none-eabi-objdump"], "-d", str(loop)], "disassembling")
    mnemonics = [line.split("\t")[2].split()[0] for line in disassembly.splitlines()
                 if re.match(r"\s+[0-9a-f]+:\t", line) and line.count("\t") >= 2]  # fmt: skip
    return {**instructions_per_step(run_on_board(elf, tools)), "mnemonics": mnemonics}


def _chain_measure(export, model, samples: int, sample_bytes: int) -> str:
    c = model.chain.name
    out = ", &acd_outputs" if model.outputs else ""
    decls = "\n".join([
        f"extern const {c}_inputs acd_replay[ACD_SAMPLES]; /* replay.s: the logged inputs */",
        "/* the replayed file holds one inputs struct per sample: the layouts must agree */",
        f"typedef char acd_replay_layout[(sizeof({c}_inputs) == {sample_bytes}u) ? 1 : -1];",
        f"static {c}_params acd_params;",
        f"static {c}_state acd_state;",
        *([f"static {c}_outputs acd_outputs;"] if model.outputs else []),
    ])  # fmt: skip
    setup = f"{c}_set_params(&acd_params);\n    {c}_reset(&acd_state);"
    call = (f"{c}_step((ACDRIVE_REAL)k * acd_params.sample_time, &acd_params, &acd_state, "
            f"&acd_replay[k]{out});")  # fmt: skip
    return measure_source(f'#include "{export.header_name}"', decls, setup, call, samples)


def struct_sizes(export, model) -> dict[str, int]:
    """Bytes of the chain's four structs in the float build (the RAM the firmware gives it:
    parameters, state, inputs, outputs), from the ctypes mirror of the same model; every
    member is 4-byte (float, uint32_t, int), laid out alike by the host and the Arm EABI."""
    import ctypes

    from acdrive.export._sil import ctypes_mirror

    types = ctypes_mirror(export, "float")
    c = model.chain.name
    return {role: ctypes.sizeof(types[f"{c}_{role}"]) for role in
            ("params", "state", "inputs", "outputs") if f"{c}_{role}" in types}  # fmt: skip


def chain_on_board(export, model, replay: bytes, samples: int, folder: Path, tools: dict) -> dict:
    """Cross-compile the float build of ``export`` (the chain ``model``), size it, and count the
    instructions of its step over ``samples`` replayed inputs (``replay``: the inputs structs,
    float32, one per sample)."""
    folder = Path(folder)
    c = model.chain.name
    (folder / export.header_name).write_text(export.header)
    (folder / export.source_name).write_text(export.source)
    chain_obj = compile_object(folder / export.source_name, folder / f"{export.name}.o", tools)
    (folder / f"replay_{c}.bin").write_bytes(replay)
    (folder / f"replay_{c}.s").write_text(
        '    .section .acd_replay, "a"\n    .balign 4\n    .global acd_replay\n'
        f'acd_replay:\n    .incbin "{folder / f"replay_{c}.bin"}"\n'
    )
    replay_obj = compile_object(folder / f"replay_{c}.s", folder / f"replay_{c}.o", tools, ())
    if samples <= 0 or len(replay) % samples:
        raise RuntimeError(f"{c}: {len(replay)} bytes of inputs are not {samples} samples")
    (folder / f"measure_{c}.c").write_text(
        _chain_measure(export, model, samples, len(replay) // samples)
    )
    measure_obj = compile_object(folder / f"measure_{c}.c", folder / f"measure_{c}.o", tools)
    elf = link([measure_obj, chain_obj, replay_obj], folder / f"{c}.elf", folder, tools)
    functions = symbol_sizes(chain_obj, tools)
    return {
        "structs": struct_sizes(export, model),
        "chain": c,
        "object": sizes(chain_obj, tools),
        "functions": {name: functions[name] for name in
                      (f"{c}_step", f"{c}_set_params", f"{c}_reset") if name in functions},
        "image": image_sizes(elf, tools),
        **instructions_per_step(run_on_board(elf, tools)),
    }  # fmt: skip


def statement_instructions(statement: str, decls: str, folder: Path, samples: int = 200) -> float:
    """Instructions of one C ``statement`` (with ``<math.h>`` and ``decls``), float build flags,
    measured by the same loop as a controller step (the call overhead included)."""
    tools = find_cross_tools()
    folder = Path(folder)
    (folder / "statement.c").write_text(
        measure_source("#include <math.h>", decls, "", statement, samples)
    )
    obj = compile_object(folder / "statement.c", folder / "statement.o", tools)
    elf = link([obj], folder / "statement.elf", folder, tools)
    return instructions_per_step(run_on_board(elf, tools))["instructions_per_step"]
