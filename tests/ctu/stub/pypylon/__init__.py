# A stand-in for Basler's camera package, which ctu-crs imports at load time (its
# basler_camera module) and these tests never use: there is no camera here.
pylon = None
genicam = None
