# Sourced by the mpm shell tests: series NAME FILE prints the rows of
# /mpm/series/NAME of run file FILE, one a line, all digits (docs/mpm.md "Output").
series() { h5dump -w 0 -A 0 -m %.17g -d "/mpm/series/$1" "$2" | sed -n 's/^ *([0-9,]*): *//p' | tr ',' '\n' | sed '/^ *$/d'; }
