"""Built-in fault plugins: crack (incl. broken tooth), chip, spall, pit (thesis 2.2)."""
