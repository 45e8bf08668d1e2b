#!/bin/sh
# Make a local stand-in for the Dockerfile's base image (no image registry is reachable here):
# Debian bookworm from Debian's archive by debootstrap, with Python 3 and the host's local CA
# certificates (package downloads here go through the host's trust store), imported as $1.
# Does nothing when the image exists already.
set -eu
tag="${1:-twoball-base:bookworm}"
if docker image inspect "$tag" >/dev/null 2>&1; then
    exit 0
fi
root="$(mktemp -d)"
trap 'rm -rf "$root"' EXIT
debootstrap --variant=minbase --include=python3,python3-venv,python3-pip,ca-certificates \
    bookworm "$root" http://deb.debian.org/debian >"$root.log" 2>&1 || { tail -20 "$root.log"; exit 1; }
if ls /usr/local/share/ca-certificates/*.crt >/dev/null 2>&1; then
    cp /usr/local/share/ca-certificates/*.crt "$root/usr/local/share/ca-certificates/"
    chroot "$root" update-ca-certificates >/dev/null
fi
rm -rf "$root/var/cache/apt/archives/"*.deb "$root/var/lib/apt/lists/"*
tar -C "$root" -c . | docker import -c 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' - "$tag" >/dev/null
