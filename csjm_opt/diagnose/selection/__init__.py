"""The selection stage of a diagnosis: scoring, pairs, rivals, the decision and its result."""
