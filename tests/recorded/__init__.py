"""Reading runs back: the dataset, damaged files, reports and plots."""
