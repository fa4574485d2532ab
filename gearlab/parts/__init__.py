"""Parts the scenario kinds share (a layer below gearlab.kinds, above the datasets and the
scenario schema): the chapter-5 training keys and units (`training`), the Bayes bound of a
simulated target (`bound`), measured target records (`measured`). A kind imports these, never
another kind (tests/test_architecture.py)."""
