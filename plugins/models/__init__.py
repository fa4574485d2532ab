"""Built-in dynamic models: ten_dof (Luo et al. 2019b), eight_dof and six_dof (Meng et al. 2020)."""
