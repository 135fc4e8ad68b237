"""The executor: segments to timed, validated dual-arm programs (split, sync, async)."""
