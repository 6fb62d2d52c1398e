# bench/callgrind_calls.awk - calls and inclusive instructions of the calls to function fn in a callgrind profile (awk -v fn=NAME)
/^c?fn=\(/ {
    id = $0; sub(/^c?fn=\(/, "", id); rest = id; sub(/\).*/, "", id)
    sub(/^[0-9]+\) ?/, "", rest)
    if (rest != "") name[id] = rest
    if ($0 ~ /^cfn=/) want = (name[id] == fn)
    next
}
/^calls=/ { if (want) { c = $0; sub(/^calls=/, "", c); split(c, f, " "); calls += f[1]; grab = 1 }; next }
grab { ir += $2; grab = 0; want = 0 }
END { if (calls) printf "%d %d\n", calls, ir }
