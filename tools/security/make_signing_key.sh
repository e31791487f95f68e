#!/usr/bin/env bash
# Makes an Ed25519 key pair for signing policy blobs (pbppo sign): NAME.pem (private, mode 600:
# keep it off the robot) and NAME.pub (public: list it in the robot file's files.trusted_keys).
# usage: make_signing_key.sh NAME [DIR]
set -euo pipefail
name=${1:?usage: make_signing_key.sh NAME [DIR]}
dir=${2:-.}
mkdir -p "$dir"
if [ -e "$dir/$name.pem" ]; then
  echo "make_signing_key: $dir/$name.pem exists; not overwritten" >&2
  exit 1
fi
(umask 077 && openssl genpkey -algorithm ed25519 -out "$dir/$name.pem")
openssl pkey -in "$dir/$name.pem" -pubout -out "$dir/$name.pub"
echo "private key: $dir/$name.pem (sign with: pbppo sign BLOB --key $dir/$name.pem)"
echo "public key:  $dir/$name.pub (trust it: files: {trusted_keys: {$name: PATH/$name.pub}} in robot.yaml)"
