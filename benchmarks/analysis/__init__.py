"""Statistics of benchmark results: intervals, paired differences, target tables, the report table
that says what to compare."""
