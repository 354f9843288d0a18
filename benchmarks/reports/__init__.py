"""Figures and videos of recorded episodes: the paper's figures, an episode's MP4."""
