"""Reading what a run recorded: the dataset, damaged files, reports, exports and `uav-tui runs`."""
