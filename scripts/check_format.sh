#!/usr/bin/env bash
# Fails when a C++ line changed since BASE (default: the commit in .ci/format-base) is not as
# clang-format-14 (.clang-format) would write it, and prints the diff that would fix it. Older
# lines that nobody touched are left as they are: formatting is enforced where code changes.
#   scripts/check_format.sh [BASE]
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:-$(cat .ci/format-base)}
command -v clang-format-14 >/dev/null || bash scripts/install-deps.sh clang-format-14
diff=$(git clang-format --binary clang-format-14 --diff "$base" -- '*.cpp' '*.hpp' 2>&1 || true)
case "$diff" in
  "" | "no modified files to format" | *"did not modify any files"* | *"clang-format did not modify"*)
    echo "format-check: every C++ line changed since ${base:0:12} is clang-formatted"
    ;;
  *)
    echo "$diff"
    echo "format-check: the lines above are not as clang-format-14 writes them (fix: git clang-format --binary clang-format-14 $base)" >&2
    exit 1
    ;;
esac
