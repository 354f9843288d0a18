"""The one resumable runner of benchmark episodes: the cache, the process pool (local or Ray), and
the two command lines on top of it (compare, the suite)."""
