"""gearlab-wear: uniform flank wear as a gearlab fault plugin (see gearlab_wear.wear)."""
