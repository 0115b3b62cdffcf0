"""Reports: self-contained HTML pages with figures (study, design comparison, measurement)."""
