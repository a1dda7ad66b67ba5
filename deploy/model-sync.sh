#!/bin/sh
# glimpse-model-sync: moves model stores between the one trainer and the many classify replicas.
#
#   glimpse-model-sync publish STORE DEST
#       Trainer side. A consistent snapshot of the live SQLite store STORE (SQLite's backup API, so a
#       Train committing meanwhile is either wholly in it or not at all) is written next to DEST,
#       switched to rollback-journal mode (a reader on a read-only mount cannot create WAL's -shm
#       file) and renamed onto DEST, so a reader sees the old file or the new one, never half of one.
#   glimpse-model-sync pull SRC STORE [SECONDS]
#       Replica side. Copies SRC into the store STORE that a running glimpse-server has open, in one
#       SQLite transaction (the backup API again); the server's next request sees the new versions
#       (it re-reads the store on every call), with no restart. With SECONDS, checks SRC for a new
#       file (inode, size, mtime) every SECONDS and pulls each new one; without, pulls once.
#       A missing SRC is not an error (nothing published yet): the store is left as it is.
#
# Needs the sqlite3 shell (Debian package sqlite3, in the image). POSIX sh: the image has no bash.
set -eu

die() { echo "glimpse-model-sync: $*" >&2; exit 1; }
log() { echo "glimpse-model-sync: $*" >&2; }
usage() { sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }

publish() {
  store=$1 dest=$2
  [ -f "$store" ] || die "publish: no store at $store"
  tmp="$dest.tmp.$$"
  trap 'rm -f "$tmp" "$tmp-journal"' EXIT
  mkdir -p "$(dirname "$dest")"
  sqlite3 "$store" ".timeout 10000" ".backup '$tmp'" || die "publish: backup of $store failed"
  mode=$(sqlite3 "$tmp" "PRAGMA journal_mode = DELETE;") || die "publish: cannot open the snapshot $tmp"
  [ "$mode" = delete ] || die "publish: snapshot kept journal mode '$mode'"
  check=$(sqlite3 "$tmp" "PRAGMA quick_check;")
  [ "$check" = ok ] || die "publish: snapshot fails quick_check: $check"
  chmod 0644 "$tmp"
  mv -f "$tmp" "$dest"
  trap - EXIT
  log "published $store as $dest ($(sqlite3 "file:$dest?mode=ro" "SELECT count(*) FROM versions;") versions)"
}

stamp() { stat -c '%i %s %Y' "$1" 2>/dev/null || true; }

pull_once() {
  src=$1 store=$2
  # immutable=1: open the published file without locks or a journal, as a read-only mount needs.
  sqlite3 "$store" ".timeout 10000" ".restore 'file:$src?immutable=1'" || { log "pull: restore of $src failed"; return 1; }
  log "pulled $src into $store ($(sqlite3 "$store" ".timeout 10000" "SELECT count(*) FROM versions;") versions)"
}

pull() {
  src=$1 store=$2 every=${3:-}
  case $every in '' | *[!0-9]*) [ -z "$every" ] || die "pull: SECONDS must be a whole number, not '$every'" ;; esac
  if [ -z "$every" ]; then
    if [ -f "$src" ]; then pull_once "$src" "$store"; else log "nothing published at $src yet"; fi
    return
  fi
  [ "$every" -gt 0 ] || die "pull: SECONDS must be > 0"
  last=""
  while :; do
    now=$(stamp "$src")
    if [ -n "$now" ] && [ "$now" != "$last" ]; then
      pull_once "$src" "$store" && last=$now
    fi
    sleep "$every"
  done
}

[ $# -ge 1 ] || usage
cmd=$1
shift
command -v sqlite3 >/dev/null || die "the sqlite3 shell is not installed"
case $cmd in
  publish) [ $# -eq 2 ] || usage; publish "$1" "$2" ;;
  pull) [ $# -ge 2 ] && [ $# -le 3 ] || usage; pull "$@" ;;
  -h | --help) usage ;;
  *) usage ;;
esac
