#!/usr/bin/env bash
# The layering of the source tree (docs/DESIGN.md, "Layout"): every #include "room/file.h" of a
# room names only a room it may use. Kernels: core < mesh, solve < the three papers' rooms
# (drying, season, wilt), each paper on the shared rooms alone; the reference twins (ref) see
# every kernel room. Harness: common < read, render < cli, all of them above the kernels.
# The kernels never include the harness. Prints each offending line; exits 1 if there is one.
set -u
cd "$(dirname "$0")/.."

allowed() {
	case "$1" in
	kernels/core) echo "core" ;;
	kernels/mesh) echo "core mesh" ;;
	kernels/solve) echo "core solve" ;;
	kernels/drying | kernels/season | kernels/wilt) echo "core mesh solve ${1#kernels/}" ;;
	kernels/ref) echo "core mesh solve drying season wilt ref" ;;
	harness/common) echo "core mesh solve drying season wilt common" ;;
	harness/read | harness/render) echo "core mesh solve drying season wilt common ${1#harness/}" ;;
	harness/cli) echo "core mesh solve drying season wilt common read render cli" ;;
	*) echo "" ;;
	esac
}

bad=0
rooms=0
for dir in kernels/*/ harness/*/; do
	room=${dir%/}
	rooms=$((rooms + 1))
	ok=$(allowed "$room")
	[ -n "$ok" ] || { echo "layer-check: $room is not a known room (add it to scripts/layer-check.sh)" >&2; bad=1; continue; }
	while IFS= read -r hit; do
		file=${hit%%:*}
		inc=$(sed -E 's/.*#include "([^"]+)".*/\1/' <<<"$hit")
		# the room's own private headers, and sibling files of its own folder
		case "$inc" in */*) ;; *) continue ;; esac
		target=${inc%%/*}
		[ "$target" = internal ] && continue
		if ! grep -qw "$target" <<<"$ok"; then
			echo "layer-check: $file includes \"$inc\": $room may use only: $ok" >&2
			bad=1
		fi
	done < <(grep -rn --include='*.c' --include='*.h' '^#include "' "$room")
done
[ $bad = 0 ] && echo "layer-check: $rooms rooms include only the rooms below them"
exit $bad
