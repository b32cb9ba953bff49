#!/usr/bin/env bash
# Seed corpora for the fuzz targets (fuzz/README.md), from files in the repository:
#   DIR/model_loader: models/*.xml and tests/malformed/*.xml as they are;
#   DIR/expr: every expression-valued attribute of those files and each item of a vector
#   attribute written with commas (one per file, entities &lt; &gt; &amp; &quot; &apos;
#   decoded).
# DIR defaults to fuzz/corpus (where `cargo fuzz run` looks). Entries are named by their
# SHA-1, so running this again adds nothing twice; it never removes what the fuzzer added.
# Usage: fuzz/seed.sh [DIR]   (from anywhere; a relative DIR is taken from the current
# directory)
set -euo pipefail
out=${1:-"$(dirname "$0")/corpus"}
mkdir -p "$out/model_loader" "$out/expr"
out=$(cd "$out" && pwd)
cd "$(dirname "$0")"
root=..

add() { # add <dir> < content
    local tmp sum
    tmp=$(mktemp)
    cat >"$tmp"
    sum=$(sha1sum "$tmp" | cut -d' ' -f1)
    mv "$tmp" "$1/$sum"
}

files=("$root"/models/*.xml "$root"/tests/malformed/*.xml)
for f in "${files[@]}"; do
    add "$out/model_loader" <"$f"
done

# Attributes whose values are expressions (or vectors of them).
attrs='function|value|mass|inertia|position|euler313|z_axis|x_axis|velocity|angular_velocity'
attrs+='|ic_angle|ic_angular_speed|ic_displacement|ic_speed|radius|stiffness|damping|length'
attrs+='|angle|preload|force|torque|start|stop|step|tolerance'
grep -ohE " ($attrs)=\"[^\"]*\"" "${files[@]}" |
    sed -E 's/^ [a-z_0-9]+="//; s/"$//; s/&lt;/</g; s/&gt;/>/g; s/&quot;/"/g; s/&apos;/'"'"'/g; s/&amp;/\&/g' |
    # Each value, and the items of a vector value (split at commas outside parentheses).
    awk '{ print; n = 0; d = 0; item = ""
           for (i = 1; i <= length($0); i++) {
               c = substr($0, i, 1)
               if (c == "(") d++
               if (c == ")") d--
               if (c == "," && d == 0) { print item; item = ""; n++ } else item = item c
           }
           if (n > 0) print item }' |
    sed -E 's/^ +//; s/ +$//' | grep -v '^$' | sort -u |
    while IFS= read -r value; do
        printf '%s' "$value" | add "$out/expr"
    done

echo "seeded $out: model_loader $(ls "$out/model_loader" | wc -l) files, expr $(ls "$out/expr" | wc -l) files"
