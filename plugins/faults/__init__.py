"""Built-in fault plugins: crack (incl. broken tooth), chip, broken_tip, spall, pit (thesis 2.2)."""
