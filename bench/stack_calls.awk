# bench/stack_calls.awk - per kernel of an `objdump -d --no-show-raw-insn` listing (its parts counted with it): libm trig calls, stack stores, stack loads (awk -v prefix=m)
#
# A kernel is a function named PREFIX_NAME; PREFIX_NAME_partK (and gcc's
# .constprop/.isra clones of it) count with it. Trig calls: call sites of
# sincos, sin and cos (one evaluation each: a kernel makes each call once).
# Stack stores and loads: instructions with an (%rsp) operand other than
# lea, a store when it is the destination (x86-64, AT&T syntax). Prints
# "NAME trig STORES LOADS" per kernel, sorted by name.
/^[0-9a-f]+ <[^>]*>:$/ {
    name = $2
    gsub(/[<>:]/, "", name)
    sub(/\.(constprop|isra|part|cold)[.0-9a-z]*$/, "", name)
    sub(/_part[0-9]+$/, "", name)
    cur = index(name, prefix "_") == 1 && name !~ /@/ ? substr(name, length(prefix) + 2) : ""
    if (cur != "")
        seen[cur] = 1
    next
}
cur == "" { next }
/\tcall/ {
    if ($0 ~ /<(sincos|sin|cos)(@plt)?>/)
        trig[cur]++
    next
}
/\tlea/ { next }
/\(%rsp\)/ {
    split($0, f, "\t")
    n = split(f[2], ops, ",")
    if (ops[n] ~ /\(%rsp\)/)
        st[cur]++
    else
        ld[cur]++
}
END {
    for (k in seen)
        printf "%s %d %d %d\n", k, trig[k], st[k], ld[k] | "sort"
}
