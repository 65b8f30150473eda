#!/usr/bin/env bash
# Mutation check: see tools/mutate/README.md. usage: run.sh [-l] [-a] [-k] [NAME_REGEX]
exec python3 "$(dirname "$0")/run.py" "$@"
