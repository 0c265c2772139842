"""Names the tests expect of the model, written here independently of the package (which reads them
from the model description): the 12 states, in the order of docs/physics.md section 3.3."""
STATES = ["alpha", "alpha_m", "beta", "beta_m", "alpha_dot", "alpha_m_dot", "beta_dot", "beta_m_dot",
          "i_R1", "i_R2", "theta_b1", "theta_b2"]
