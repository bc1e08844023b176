// insane, converted from a kdrt scene by kdrt-bench povray (500x500).
// Render: povray +W500 +H500 -D -A +FN File_Gamma=1.0 +I<this file>
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 15 ambient_light rgb <0.05, 0.05, 0.05> }
background { color rgb <0, 0, 0> }
camera {
  perspective
  location <0, 0, -0.95>
  sky <0, 1, 0>
  up y
  right -x*1
  angle 65
  look_at <0, -0.1, 1>
}
light_source { <0, 0.9, 0> color rgb <0.5, 0.5, 0.5> }
#declare M0_white = material {
  texture {
    pigment { color rgb <0.8, 0.8, 0.8> }
    finish { ambient 0.3 diffuse 0.3 phong 0.2 phong_size 30 reflection { 0.7 } }
  }
}
#declare M1_red = material {
  texture {
    pigment { color rgb <0.9, 0.15, 0.1> }
    finish { ambient 0.3 diffuse 0.3 phong 0.2 phong_size 30 reflection { 0.7 } }
  }
}
#declare M2_green = material {
  texture {
    pigment { color rgb <0.1, 0.8, 0.2> }
    finish { ambient 0.3 diffuse 0.3 phong 0.2 phong_size 30 reflection { 0.7 } }
  }
}
#declare M3_mirror = material {
  texture {
    pigment { color rgb <0.9, 0.9, 0.9> }
    finish { ambient 0.05 diffuse 0.05 phong 0.8 phong_size 200 reflection { 0.95 } }
  }
}
#declare M4_gold = material {
  texture {
    pigment { color rgb <0.95, 0.75, 0.2> }
    finish { ambient 0.3 diffuse 0.3 phong 0.7 phong_size 80 reflection { 0.7 } }
  }
}
#declare M5_block = material {
  texture {
    pigment { color rgb <0.6, 0.6, 0.9> }
    finish { ambient 0.3 diffuse 0.3 phong 0.4 phong_size 50 reflection { 0.7 } }
  }
}
sphere { <-0.45, -0.62, 0.35>, 0.38 material { M3_mirror } }
sphere { <0.45, -0.75, -0.25>, 0.25 material { M4_gold } }
mesh {
  triangle { <-1, -1, 1>, <1, -1, 1>, <1, 1, 1> }
  triangle { <-1, -1, 1>, <1, 1, 1>, <-1, 1, 1> }
  triangle { <-1, -1, -1>, <-1, 1, -1>, <1, 1, -1> }
  triangle { <-1, -1, -1>, <1, 1, -1>, <1, -1, -1> }
  triangle { <-1, -1, -1>, <1, -1, -1>, <1, -1, 1> }
  triangle { <-1, -1, -1>, <1, -1, 1>, <-1, -1, 1> }
  triangle { <-1, 1, -1>, <-1, 1, 1>, <1, 1, 1> }
  triangle { <-1, 1, -1>, <1, 1, 1>, <1, 1, -1> }
  material { M0_white }
}
mesh {
  triangle { <-1, -1, -1>, <-1, -1, 1>, <-1, 1, 1> }
  triangle { <-1, -1, -1>, <-1, 1, 1>, <-1, 1, -1> }
  material { M1_red }
}
mesh {
  triangle { <1, -1, -1>, <1, 1, -1>, <1, 1, 1> }
  triangle { <1, -1, -1>, <1, 1, 1>, <1, -1, 1> }
  material { M2_green }
}
mesh {
  triangle { <0.15, -1, 0.25>, <0.15, 0.1, 0.25>, <0.6, 0.1, 0.25> }
  triangle { <0.15, -1, 0.25>, <0.6, 0.1, 0.25>, <0.6, -1, 0.25> }
  triangle { <0.15, -1, 0.7>, <0.6, -1, 0.7>, <0.6, 0.1, 0.7> }
  triangle { <0.15, -1, 0.7>, <0.6, 0.1, 0.7>, <0.15, 0.1, 0.7> }
  triangle { <0.15, -1, 0.25>, <0.15, -1, 0.7>, <0.15, 0.1, 0.7> }
  triangle { <0.15, -1, 0.25>, <0.15, 0.1, 0.7>, <0.15, 0.1, 0.25> }
  triangle { <0.6, -1, 0.25>, <0.6, 0.1, 0.25>, <0.6, 0.1, 0.7> }
  triangle { <0.6, -1, 0.25>, <0.6, 0.1, 0.7>, <0.6, -1, 0.7> }
  triangle { <0.15, -1, 0.25>, <0.6, -1, 0.25>, <0.6, -1, 0.7> }
  triangle { <0.15, -1, 0.25>, <0.6, -1, 0.7>, <0.15, -1, 0.7> }
  triangle { <0.15, 0.1, 0.25>, <0.15, 0.1, 0.7>, <0.6, 0.1, 0.7> }
  triangle { <0.15, 0.1, 0.25>, <0.6, 0.1, 0.7>, <0.6, 0.1, 0.25> }
  material { M5_block }
}
