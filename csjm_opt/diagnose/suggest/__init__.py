"""The next experiment: candidate load cycles, the lab's dead weights, the suggestion and its protocol."""
