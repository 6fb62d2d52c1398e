# cycles.awk - Cortex-M4 cycles of the instructions QEMU executed, from the Technical Reference Manual's tables.
#
#   awk -f cycles.awk DISASSEMBLY TRACE
#
# DISASSEMBLY is `arm-none-eabi-objdump -d ELF`; TRACE is QEMU's
# `-singlestep -d exec,nochain` log (one "Trace" line per executed
# instruction, its address the second field inside [...]). The windows are
# opened at the entry of the marker functions mark_fk_plain, mark_fk_pred
# and mark_va (stewart.c, -DSTEP_TRACE) and closed at mark_off; the marker
# functions' own instructions (a bx lr each) are left out, the bl calling
# them is counted, 1 instruction a window.
#
# QEMU counts instructions, not cycles, so each executed instruction is
# charged its cycles from the Cortex-M4 TRM (ARM DDI 0439B, table 3-1,
# "Cortex-M4 instruction set summary", and table 7-1, "FPU instruction
# set"), under two sets of assumptions, printed as a range:
#   high (pessimistic): every taken branch refills the pipeline with P = 3
#     (the TRM's P is 1 to 3), every load and store takes its full 2 cycles
#     (no pipelining of neighbours), IT takes 1 cycle, SDIV/UDIV 12;
#   low (optimistic): P = 1, a single load or store right after another one
#     takes 1 (the TRM's note on neighbouring loads and stores), IT is
#     folded (0), SDIV/UDIV 2.
# Both: zero-wait-state memory (the MPS2's SRAM; flash wait states on a
# real part add to both), VDIV and VSQRT 14 cycles with no overlap,
# VMLA/VFMA and their variants 3, other single-precision data processing 1,
# VLDR/VSTR 2 (.64: 3), VLDM/VSTM/VPUSH/VPOP 1 + N (registers), LDM/STM/
# PUSH/POP 1 + N (+ P when they load pc), LDRD/STRD 3, MUL/MLA/MLS/SMULL/
# UMULL/SMLAL/UMLAL 1, a conditional branch not taken 1, taken 1 + P, B/
# BL/BX/BLX/CBZ/CBNZ taken 1 + P, an instruction writing pc 1 + P;
# a conditional instruction inside an IT block is charged as if executed.
# Whether a branch was taken is read from the trace: the next executed
# address is not the one after the branch.

function regcount(ops,    list, n, parts, i, a, b, r) {
    if (!match(ops, /\{[^}]*\}/))
        return 1
    list = substr(ops, RSTART + 1, RLENGTH - 2)
    n = 0
    split(list, parts, ",")
    for (i in parts) {
        r = parts[i]
        gsub(/ /, "", r)
        if (r ~ /-/) {          # a range such as s16-s23 or d8-d9
            split(r, a, "-")
            b = substr(a[2], 2) - substr(a[1], 2) + 1
            n += (substr(a[1], 1, 1) == "d") ? 2 * b : b
        } else
            n += (substr(r, 1, 1) == "d") ? 2 : 1
    }
    return n
}

# The class of one instruction: sets base cost (high, low), whether it can
# branch (br), and whether it is a single load or store (ls).
function classify(pc, m, ops,    base, cond) {
    sub(/\.(w|n)$/, "", m)
    base = m
    sub(/\..*$/, "", base)
    cond = "(eq|ne|cs|cc|hs|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al)"
    hi[pc] = 1; lo[pc] = 1; br[pc] = 0; ls[pc] = 0; pcw[pc] = 0
    if (base ~ ("^(b|bl|blx|bx)" cond "?$") || base ~ /^cbn?z$/) {
        br[pc] = (base ~ ("^b" cond "$") || base ~ /^cbn?z$/) ? 1 : 2   # 2: always taken
        return
    }
    if (base ~ /^tb[bh]$/) { hi[pc] = 2; lo[pc] = 2; br[pc] = 2; return }
    if (base ~ /^it[te]*$/) { hi[pc] = 1; lo[pc] = 0; return }
    if (base ~ /^(push|pop|ldm|stm)/ || base ~ /^(ldmia|ldmdb|stmia|stmdb)/) {
        hi[pc] = lo[pc] = 1 + regcount(ops)
        if (base !~ /^(push|stm)/ && ops ~ /pc/) { br[pc] = 2 }
        return
    }
    if (base ~ /^(vpush|vpop|vldm|vstm)/) { hi[pc] = lo[pc] = 1 + regcount(ops); return }
    if (base ~ /^(ldrd|strd)/) { hi[pc] = lo[pc] = 3; return }
    if (base ~ /^(ldr|str|ldrex|strex)/) {
        hi[pc] = 2; lo[pc] = 2; ls[pc] = 1
        if (base ~ /^ldr/ && ops ~ /^pc,/) { br[pc] = 2 }
        return
    }
    if (base ~ /^(vldr|vstr)/) {
        hi[pc] = lo[pc] = (m ~ /64/ || ops ~ /^d/) ? 3 : 2
        ls[pc] = 1
        return
    }
    if (base ~ /^(vdiv|vsqrt)/) { hi[pc] = lo[pc] = 14; return }
    if (base ~ /^(vmla|vmls|vnmla|vnmls|vfma|vfms|vfnma|vfnms)/) { hi[pc] = lo[pc] = 3; return }
    if (base ~ /^vmov/) {
        # two core registers (vmov r0, r1, d0 or s0, s1, r0, r1): 2
        hi[pc] = lo[pc] = (gsub(/(^|[ ,])(r[0-9]+|ip|lr|fp|sl)/, "&", ops) >= 2) ? 2 : 1
        return
    }
    if (base ~ /^v/) return
    if (base ~ /^[su]div/) { hi[pc] = 12; lo[pc] = 2; return }
    if (ops ~ /^pc,/) { pcw[pc] = 1 }
}

# objdump lines: "    5ffc:	b530      	push	{r4, r5, lr}"
FNR == NR {
    if ($0 ~ /^[0-9a-f]+ <[^>]+>:$/) {
        fn = $2
        gsub(/[<>:]/, "", fn)
        addr = $1
        sub(/^0+/, "", addr)
        if (fn ~ /^mark_(fk_plain|fk_pred|va|off)$/)
            marker[addr] = substr(fn, 6)
        infn = fn
        next
    }
    if (split($0, f, "\t") >= 3 && f[1] ~ /^ *[0-9a-f]+:$/) {
        a = f[1]
        gsub(/[ :]/, "", a)
        hex = f[2]
        gsub(/ /, "", hex)
        size[a] = length(hex) / 2
        op = f[3]
        gsub(/ /, "", op)
        classify(a, op, f[4])
        inmark[a] = infn ~ /^mark_(fk_plain|fk_pred|va|off)$/
    }
    next
}

function hexval(s,    i, v, c) {
    v = 0
    s = tolower(s)
    for (i = 1; i <= length(s); i++) {
        c = index("0123456789abcdef", substr(s, i, 1)) - 1
        v = v * 16 + c
    }
    return v
}

# Settles the previous instruction now that the next address is known.
function settle(next_addr,    taken, h, l) {
    if (prev == "" || win == "")
        return
    h = hi[prev]; l = lo[prev]
    if (br[prev] == 2 || pcw[prev])
        taken = 1
    else if (br[prev] == 1)
        taken = (hexval(next_addr) != hexval(prev) + size[prev])
    else
        taken = 0
    if (taken) { h += 3; l += 1 }
    if (ls[prev] && prevls) l = 1
    instr[win]++
    chigh[win] += h
    clow[win] += l
    prevls = ls[prev]
}

/^Trace / {
    if (!match($0, /\[[0-9a-f]+\/[0-9a-f]+\//))
        next
    s = substr($0, RSTART + 1, RLENGTH - 2)
    split(s, p, "/")
    a = p[2]
    sub(/^0+/, "", a)
    settle(a)
    if (a in marker) {
        w = marker[a]
        win = (w == "off") ? "" : w
        if (win != "")
            windows[win]++
        prev = ""
        prevls = 0
        next
    }
    if (!(a in size)) {         # not in the disassembly (should not happen)
        unknown++
        prev = ""
        next
    }
    prev = inmark[a] ? "" : a
}

END {
    split("fk_plain fk_pred va", order, " ")
    name["fk_plain"] = "forward kinematics from the previous pose"
    name["fk_pred"] = "forward kinematics with the predictor"
    name["va"] = "velocity and acceleration"
    for (i = 1; i <= 3; i++) {
        w = order[i]
        n = windows[w]
        if (n == 0) {
            printf "%s: no window in the trace\n", name[w]
            continue
        }
        printf "%s: %.0f instructions, %.0f to %.0f cycles (mean of %d)\n", name[w],
               instr[w] / n, clow[w] / n, chigh[w] / n, n
    }
    if (unknown > 0)
        printf "warning: %d executed addresses not in the disassembly\n", unknown
}
