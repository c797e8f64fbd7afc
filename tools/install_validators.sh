#!/usr/bin/env bash
# Install the external validators the converter tests run into .tools/ (gitignored):
#   .tools/node_modules/gltf-validator   Khronos glTF-Validator, pinned by
#                                        tools/validators/package-lock.json
# USD validation needs nothing extra: usd-core's pxr.UsdValidation is used.
# Needs node >= 18 and npm. Usage: tools/install_validators.sh  (from anywhere)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tools="${PLANEFMT_TOOLS:-$root/.tools}"
command -v npm >/dev/null || { echo "install_validators: npm not found" >&2; exit 1; }
mkdir -p "$tools"
cp "$root/tools/validators/package.json" "$root/tools/validators/package-lock.json" "$tools/"
# npm ci: exactly the locked versions, checked against their recorded hashes
npm ci --prefix "$tools" --no-audit --no-fund --ignore-scripts --loglevel=error
version="$(node -p "require('$tools/node_modules/gltf-validator/package.json').version")"
echo "glTF-Validator $version in $tools"
