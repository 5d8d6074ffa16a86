"""Data on the way in and out: activity and EMG files, marker CSV, results files."""
