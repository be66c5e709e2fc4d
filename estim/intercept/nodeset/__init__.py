"""The node set: exact slices at time-to-go nodes, sound bounds between them."""
