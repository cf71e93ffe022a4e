#!/bin/sh
# SPDX-License-Identifier: MIT
# core.rt_symbols: the real-time library calls no allocator, opens no file, takes no mutex and
# knows nothing of YAML or URDF. nm -u lists what each object of libmca_core.a needs from outside; any
# forbidden name fails the test, printed with its object file. The same check on libmca_model.a must find
# the YAML and URDF readers there (the check is not vacuous: it can fail).
# usage: check_rt_symbols.sh NM LIBMCA_CORE.a LIBMCA_MODEL.a
set -eu
NM=$1
CORE=$2
MODEL=$3

# allocation (C and C++ operator new/delete in all their variants), file opening, mutexes, the parsers
FORBIDDEN='^(fopen|fopen64|fdopen|freopen|freopen64|malloc|calloc|realloc|reallocarray|free|aligned_alloc|posix_memalign|memalign|valloc|pvalloc|strdup|strndup|getline|getdelim)$|^_Zn[wa]|^_Zd[la]|^pthread_mutex_|[Yy][Aa][Mm][Ll]|[Uu][Rr][Dd][Ff]|TiXml'

# "OBJECT SYMBOL" for every forbidden undefined symbol of archive $1
offending() {
    # nm -A -u on an archive: "ARCHIVE:OBJECT:                 U SYMBOL" (the symbol may carry @VERSION)
    "$NM" -A -u "$1" | awk -v re="$FORBIDDEN" '
        NF >= 2 && $(NF - 1) == "U" {
            sym = $NF
            sub(/@.*/, "", sym)
            n = split($1, part, ":")
            obj = n >= 2 ? part[n - 1] : part[1]
            if (sym ~ re) print obj, sym
        }'
}

for lib in "$CORE" "$MODEL"; do
    if [ ! -f "$lib" ]; then
        echo "FAIL $lib: no such library"
        exit 1
    fi
done
fail=0

core_bad=$(offending "$CORE")
if [ -n "$core_bad" ]; then
    echo "FAIL $(basename "$CORE"): forbidden undefined symbols (object symbol):"
    echo "$core_bad" | sed 's/^/  /'
    fail=1
else
    echo "ok   $(basename "$CORE"): $("$NM" -u "$CORE" | grep -c ' U ') undefined symbols, none forbidden"
fi

# the check itself: it must see the parsers and the allocator in the model library
model_bad=$(offending "$MODEL")
for want in cyaml urdf; do
    if echo "$model_bad" | grep -qi "$want"; then
        echo "ok   $(basename "$MODEL"): the check finds $want symbols: $(echo "$model_bad" | grep -i "$want" | head -3 | awk '{printf "%s(%s) ", $2, $1}')"
    else
        echo "FAIL $(basename "$MODEL"): the check finds no $want symbol there (is it vacuous?)"
        fail=1
    fi
done

[ $fail -eq 0 ] && echo PASSED || echo FAILED
exit $fail
