//! Kinematics: spline routes and wave perturbations (see submodules).
