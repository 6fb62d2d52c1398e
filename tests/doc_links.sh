#!/bin/sh
# tests/doc_links.sh MECHC - the documentation cites only what exists: in
# README.md, doc/*.md and the other Markdown pages every relative link (and
# image) names a file of the repository, every #anchor a heading of its
# target (GitHub's slugs), and every backticked repository path (a span
# with no blank whose first part is a top-level entry, say
# `generator/emit/emit.c` or `runtime/*.c`) exists, or is a program built
# from its .c (`tests/browser/pngdiff`). Fenced code blocks are not
# read. MECHC is not run; it is taken for the harness only.
#
#   sh tests/doc_links.sh build/mechc
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin doc_links "${1:-build/mechc}"
cd "$root" || exit 2

docs="README.md examples/README.md examples/RENDERING.md examples/firmware/README.md tests/fuzz/README.md"
for f in doc/*.md; do [ -f "$f" ] && docs="$docs $f"; done

# Every heading's slug, as "FILE#slug", for every Markdown file cited.
find . -name '*.md' -not -path './build/*' -not -path './.git/*' | sed 's|^\./||' > "$tmp/md"
# shellcheck disable=SC2046
awk '
FNR == 1 { fence = 0; delete seen }
/^[ \t]*```/ { fence = !fence; next }
fence { next }
/^#+ / {
    h = $0
    sub(/^#+ +/, "", h)
    h = tolower(h)
    gsub(/[^a-z0-9 _-]/, "", h)   # punctuation and non-ASCII bytes go
    gsub(/ /, "-", h)
    s = h
    if (h in seen) s = h "-" seen[h]
    seen[h]++
    print FILENAME "#" s
}' $(cat "$tmp/md") > "$tmp/anchors"

# Every file and folder of the repository (not build/ or .git/).
find . -not -path './build' -not -path './build/*' -not -path './.git' \
    -not -path './.git/*' | sed 's|^\./||' > "$tmp/files"

# Every citation checked in one pass: links (and images) outside fenced
# code, then backticked spans with no blank whose first part is a
# top-level entry.
# shellcheck disable=SC2086
awk -v files="$tmp/files" -v anchors="$tmp/anchors" '
BEGIN {
    while ((getline f < files) > 0) {
        have[f] = 1
        if (f !~ /\//) top[f] = 1
    }
    while ((getline a < anchors) > 0) slug[a] = 1
    checked = 0
}
function bad(msg) { print FILENAME ":" FNR ": " msg; failed++ }
function normal(p,    n, part, out, i, k) {   # a/b/../c -> a/c
    n = split(p, part, "/")
    k = 0
    for (i = 1; i <= n; i++) {
        if (part[i] == "" || part[i] == ".") continue
        if (part[i] == "..") { if (k > 0) k--; continue }
        out[++k] = part[i]
    }
    p = ""
    for (i = 1; i <= k; i++) p = p (i > 1 ? "/" : "") out[i]
    return p
}
function exists(p,    re, f) {
    if (p in have || (p ".c") in have) return 1    # or a program built from p.c
    if (p !~ /[*?]/) return 0
    re = p
    gsub(/\./, "\\.", re); gsub(/\*/, "[^/]*", re); gsub(/\?/, "[^/]", re)
    for (f in have) if (f ~ ("^" re "$")) return 1
    return 0
}
function link(t,    path, anchor, dir, resolved) {
    if (t ~ /^(https?|mailto):/) return
    path = t; anchor = ""
    if (index(t, "#")) { path = substr(t, 1, index(t, "#") - 1); anchor = substr(t, index(t, "#") + 1) }
    if (path == "") resolved = FILENAME
    else {
        dir = FILENAME; if (!sub(/\/[^\/]*$/, "", dir)) dir = ""
        resolved = normal(dir "/" path)
        if (!exists(resolved)) { bad("the link (" t ") names no file"); return }
    }
    if (anchor != "" && !((resolved "#" anchor) in slug)) {
        bad("the link (" t "): no heading of " resolved " has the anchor #" anchor); return
    }
    checked++
}
function path(t,    first) {
    if (t !~ /\//) return
    first = t; sub(/\/.*/, "", first)
    if (!(first in top)) return
    sub(/\/$/, "", t)
    if (!exists(t)) { bad("`" t "` is not in the repository"); return }
    checked++
}
FNR == 1 { fence = 0 }
/^[ \t]*```/ { fence = !fence; next }
fence { next }
{
    line = $0
    while (match(line, /\]\([^) ]+\)/)) {
        link(substr(line, RSTART + 2, RLENGTH - 3))
        line = substr(line, RSTART + RLENGTH)
    }
    line = $0
    while (match(line, /`[^` ]+`/)) {
        path(substr(line, RSTART + 1, RLENGTH - 2))
        line = substr(line, RSTART + RLENGTH)
    }
}
END { print checked > "/dev/stderr" }' $docs > "$tmp/failures" 2> "$tmp/count"

while read -r msg; do bad "$msg"; done < "$tmp/failures"
checked=$(cat "$tmp/count")
if [ "$checked" -gt 100 ]; then ok; else bad "only $checked citations checked: the extraction is broken"; fi

# Nothing in the tree cites an issue number of the tracker or a page that
# was never written (a dynamics page once cited): files describe what is.
# (The patterns are spelled so that this file does not match them.)
word=ssue
grep -rnIE --exclude-dir='build*' --exclude-dir=.git --exclude-dir=__pycache__ \
    "[Ii]${word}s? ?#?[0-9]+|DYN[.]md" . > "$tmp/cites"
while read -r line; do bad "cites the tracker or a missing page: $line"; done < "$tmp/cites"
[ -s "$tmp/cites" ] || ok
suite_end
