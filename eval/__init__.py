"""The comparison study: transition pairs, metrics, statistics, figures, benchmarks."""
