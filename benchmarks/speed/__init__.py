"""Speed benchmarks that print figures (`auv-gym speed`)."""
