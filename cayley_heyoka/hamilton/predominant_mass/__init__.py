"""Hamilton's system with one predominant mass (Second Essay, §§ on the planets): bodies about a
dominant central mass in relative coordinates, his split H = H₁ + H₂ into Keplerian motions and
their mutual disturbance, and its consistency check (``hamiltonian.model =
"predominant_mass"``)."""
